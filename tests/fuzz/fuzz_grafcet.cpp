// libFuzzer target: the Grafcet text parser (services/grafcet), what the cell
// and every edge run on a supervisor pushed as data. Any input must give a
// Grafcet or diagnostics, never a crash, a hang or undefined behaviour.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "smc/grafcet/parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto r = smc::grafcet::parse(text, "fuzz.grafcet");
  if (r.ok() == !r.errors.empty()) __builtin_trap();  // one or the other, always
  return 0;
}
