#pragma once
// The operation supervisor's Grafcet bound to the edge's vocabulary: its
// level and impulse actions name modules (A, B, … ; "X*" resets X), its
// inputs are the state supervisor's receptivities a–e (paper, Table 2)
// and f–h (beyond the paper: tool breakage, spindle speed change).
// Checked cheaply first (names, sizes), then verified exhaustively. Used by
// the edge's operation supervisor and by configuration validation in cell
// and edge alike. Not for the real-time loop (allocates).

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "smc/grafcet/model.hpp"
#include "smc/grafcet/types.hpp"
#include "smc/supervision/modules.hpp"
#include "smc/supervision/parameters.hpp"

namespace smc::supervision {

// Receptivities of the state supervisor (paper, Table 2), as input bits.
enum Receptivity : uint8_t {
  kInputA = 0,  // a: operator feed hold active
  kInputB = 1,  // b: tool-part contact
  kInputC = 2,  // c: chatter signalled by the operator
  kInputD = 3,  // d: chatter detected automatically
  kInputE = 4,  // e: chatter suppression routine complete
  // Beyond the paper (SMC II+, cell/grafcets/smc2_plus.grafcet):
  kInputF = 5,  // f: tool breakage detected (module N, latched until N is reset)
  kInputG = 6,  // g: spindle speed change complete (module O: at the new speed)
  kInputH = 7,  // h: the spindle speed was changed in this pass already (module O)
};
inline constexpr int kReceptivityCount = 8;

struct BoundGrafcet {
  grafcet::Grafcet grafcet;
  // Grafcet action index → the module's bit.
  std::array<ModuleMask, grafcet::kMaxActions> action_module{};
  // Receptivity a..e → the Grafcet's input index; -1 when the Grafcet does
  // not read it.
  std::array<int, kReceptivityCount> input_index{};
};

// What checking one Grafcet may cost. The shipped SMC II needs 1,056
// evolutions and a few thousand rounds; the defaults allow about a hundred
// times that, so a supervisor's Grafcet is checked in well under 100 ms and
// a hostile one is refused instead of holding up its caller.
struct CheckBudget {
  std::size_t max_text_bytes = 64 * 1024;   // before parsing
  std::uint64_t max_work = 500'000;         // evolution rounds (deterministic)
  std::chrono::milliseconds max_time{500};  // wall-clock guard
};

// Refuses a text over the budget's size, parses it (named `source_name` in
// messages), checks that every action is a module in `allowed` and every
// input a receptivity a–h, then verifies it within the budget. Throws
// ConfigError: parse errors as "file:line:col: …", a bad action or input
// naming it, a failed or over-budget verification with the verifier's report.
BoundGrafcet bind_grafcet(std::string_view text, std::string_view source_name, ModuleMask allowed,
                          const CheckBudget& budget = {});

}  // namespace smc::supervision
