// libFuzzer target: the tap test's CSV reader and the modal fit
// (services/machining frf.hpp), which take a file from outside software.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "smc/machining/frf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto frf = smc::machining::parse_frf_csv(text, "fuzz.csv");
    for (const auto& [dir, points] : frf) {
      if (points.size() > 4000) continue;  // the fit is not what is fuzzed for size
      try {
        (void)smc::machining::fit_modes(points, 2);
      } catch (const std::invalid_argument&) {
      }
    }
  } catch (const std::runtime_error&) {
    // refused, naming line and column
  }
  return 0;
}
