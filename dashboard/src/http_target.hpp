#pragma once
// The request target of an HTTP request (RFC 9112 origin-form: path and
// query), percent-decoded into segments and query pairs. Outside input:
// fuzzed (tests/fuzz/fuzz_http.cpp).

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace smc::dashboard {

struct Target {
  std::vector<std::string> segments;  // decoded path segments, empty ones dropped
  std::vector<std::pair<std::string, std::string>> query;
  std::string path;  // decoded path
};

// Percent-decodes `s` ('+' as a space in a query); nullopt for a raw control
// character, a truncated or invalid escape, or one that decodes to NUL.
std::optional<std::string> percent_decode(std::string_view s, bool plus_is_space);

// nullopt unless the target starts with '/' and every escape is valid.
std::optional<Target> parse_target(std::string_view target);

}  // namespace smc::dashboard
