#pragma once
// Number formatting for error messages (internal).

#include <cstdio>
#include <string>

namespace smc::machining::detail {

// Shortest readable form: 1.7, 0.0001, 1e+20, nan.
inline std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
inline std::string fmt(int v) { return std::to_string(v); }

}  // namespace smc::machining::detail
