#include "smc/common/diagnostic.hpp"

#include <charconv>
#include <cstdio>

namespace smc::common {

namespace {

void append_one_line(std::string& out, std::string_view s) {
  for (char c : s) out.push_back(c == '\n' || c == '\r' ? ' ' : c);
}

}  // namespace

std::string Diagnostic::str() const {
  std::string out;
  if (!where.empty()) {
    append_one_line(out, where);
    out += ": ";
  }
  append_one_line(out, message);
  if (!fix.empty()) {
    out += "; fix: ";
    append_one_line(out, fix);
  }
  return out;
}

std::string Diagnostics::str(std::size_t limit) const {
  std::string out;
  const std::size_t shown = list_.size() < limit ? list_.size() : limit;
  for (std::size_t i = 0; i < shown; ++i) {
    if (i) out += '\n';
    out += list_[i].str();
  }
  if (list_.size() > shown) {
    out += "\nand " + std::to_string(list_.size() - shown) + " more problem" +
           (list_.size() - shown == 1 ? "" : "s");
  }
  return out;
}

DiagnosticError::DiagnosticError(Diagnostics d, std::size_t limit)
    : std::runtime_error(d.str(limit)), diagnostics_(std::move(d)) {}

DiagnosticError::DiagnosticError(Diagnostic d)
    : std::runtime_error(d.str()), diagnostics_([&] {
        Diagnostics l;
        l.add(std::move(d));
        return l;
      }()) {}

std::string quote(std::string_view value, std::size_t max_chars) {
  std::string out = "'";
  std::size_t n = 0;
  for (char c : value) {
    if (n == max_chars) break;
    const auto u = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\'') {
      out += "\\'";
    } else if (u < 0x20 || u == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", u);
      out += buf;
    } else {
      out += c;
    }
    ++n;
  }
  out += '\'';
  if (value.size() > max_chars) out += "…(" + std::to_string(value.size()) + " bytes)";
  return out;
}

std::string number(double value) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);  // shortest that reads back the same
  return std::string(buf, r.ptr);
}

}  // namespace smc::common
