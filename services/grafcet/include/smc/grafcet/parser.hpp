#pragma once
// The Grafcet text format (see services/grafcet/README.md): parse a whole
// file, report every error with file:line:col, and return a Grafcet only when
// there was none. Not for the real-time loop (allocates).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "smc/grafcet/model.hpp"

namespace smc::grafcet {

struct Diagnostic {
  std::string file;
  SourceLocation where;  // line 0: the whole file (e.g. it cannot be read)
  std::string message;
  // "file:line:col: error: message"
  std::string str() const;
};

struct ParseResult {
  std::optional<Grafcet> grafcet;  // set if and only if errors is empty
  std::vector<Diagnostic> errors;  // in file order
  bool ok() const noexcept { return grafcet.has_value(); }
};

// `file` names the text in diagnostics and in Grafcet::source().
ParseResult parse(std::string_view text, std::string_view file = "<text>");
ParseResult parse_file(const std::string& path);

}  // namespace smc::grafcet
