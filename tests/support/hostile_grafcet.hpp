#pragma once
// Hostile operation-supervisor Grafcets for tests and benchmarks.

#include <string>

namespace smc::test {

// One input, cycles of coprime lengths (3, 4, 5, 7, 11, 13, 17: 60 steps)
// that all advance on each rise of a: 1,021,020 reachable situations.
// Padded with comments to `pad_to` bytes when that is larger.
inline std::string huge_state_space_grafcet(std::size_t pad_to = 0) {
  std::string g = "grafcet hostile \"many coprime cycles\"\ninput a \"a\"\n";
  int step = 1, transition = 1;
  for (int len : {3, 4, 5, 7, 11, 13, 17}) {
    const int first = step;
    for (int k = 0; k < len; ++k, ++step) {
      g += "step " + std::to_string(step) + (k == 0 ? " initial" : "") + " \"s\"\n";
    }
    for (int k = 0; k < len; ++k) {
      g += "transition " + std::to_string(transition++) + ": " + std::to_string(first + k) +
           " -> " + std::to_string(first + (k + 1) % len) + " when ↑a\n";
    }
  }
  while (g.size() + 64 < pad_to) g += "# padding to the size limit of a configuration's Grafcet\n";
  return g;
}

}  // namespace smc::test
