#pragma once
// One diagnostic type for everything that checks outside input: the Grafcet
// parser, the document loaders, configuration validation and the store.
//
//   where    "file:line:col" for text, or a field path such as
//            "supervisor_config.operation.teeth" for a document
//   message  what is wrong, naming the value (quoted and bounded)
//   fix      what to do about it; empty when it goes without saying
//
// A Diagnostics list collects every problem instead of stopping at the
// first, and prints at most `limit` of them followed by "and K more", so a
// 10 MB garbage file never becomes 40 MB of errors. Not for the real-time
// loop (allocates).

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace smc::common {

struct Diagnostic {
  std::string where;
  std::string message;
  std::string fix;

  // "where: message; fix: fix" on one line (newlines in the parts become
  // spaces, so a diagnostic is always one line); "message; fix: fix" when
  // `where` is empty (the message names its place itself).
  std::string str() const;
};

class Diagnostics {
 public:
  static constexpr std::size_t kDefaultLimit = 20;

  void add(Diagnostic d) { list_.push_back(std::move(d)); }
  void add(std::string where, std::string message, std::string fix = {}) {
    list_.push_back({std::move(where), std::move(message), std::move(fix)});
  }
  void append(const Diagnostics& other) {
    list_.insert(list_.end(), other.list_.begin(), other.list_.end());
  }
  bool ok() const noexcept { return list_.empty(); }
  bool empty() const noexcept { return list_.empty(); }
  std::size_t size() const noexcept { return list_.size(); }
  const std::vector<Diagnostic>& list() const noexcept { return list_; }
  auto begin() const noexcept { return list_.begin(); }
  auto end() const noexcept { return list_.end(); }

  // One diagnostic per line, at most `limit`, then "and K more problems".
  std::string str(std::size_t limit = kDefaultLimit) const;

 private:
  std::vector<Diagnostic> list_;
};

// Thrown where a caller cannot go on: what() is Diagnostics::str(), and the
// structured list stays available.
class DiagnosticError : public std::runtime_error {
 public:
  explicit DiagnosticError(Diagnostics d, std::size_t limit = Diagnostics::kDefaultLimit);
  explicit DiagnosticError(Diagnostic d);
  const Diagnostics& diagnostics() const noexcept { return diagnostics_; }

 private:
  Diagnostics diagnostics_;
};

// A value for a message: quoted, control characters escaped, cut to
// `max_chars` with "…(N bytes)" so no field is ever echoed whole.
std::string quote(std::string_view value, std::size_t max_chars = 64);
// The same for a number, as the shortest text that reads back the same.
std::string number(double value);

}  // namespace smc::common
