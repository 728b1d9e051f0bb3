#pragma once
// The Grafcet text format (see services/grafcet/README.md): parse a whole
// file, report every error with file:line:col, and return a Grafcet only when
// there was none. Not for the real-time loop (allocates).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "smc/common/diagnostic.hpp"
#include "smc/grafcet/model.hpp"

namespace smc::grafcet {

// A parse problem: the project's diagnostic (where = "file:line:col", or
// "file" for the whole file), with the file and position kept as values too.
// Messages longer than 240 characters are cut ("…(N bytes)"), so a huge
// token is never echoed whole.
struct Diagnostic : common::Diagnostic {
  Diagnostic(std::string file_name, SourceLocation at, std::string what);
  std::string file;
  SourceLocation location;  // line 0: the whole file (e.g. it cannot be read)
  // Compiler style, which editors jump to: "file:line:col: error: message".
  std::string str() const;
};

struct ParseResult {
  std::optional<Grafcet> grafcet;  // set if and only if errors is empty
  // In file order; at most kMaxErrors, then one "and K more errors".
  std::vector<Diagnostic> errors;
  bool ok() const noexcept { return grafcet.has_value(); }
};
inline constexpr std::size_t kMaxErrors = 50;

// `file` names the text in diagnostics and in Grafcet::source().
ParseResult parse(std::string_view text, std::string_view file = "<text>");
ParseResult parse_file(const std::string& path);

}  // namespace smc::grafcet
