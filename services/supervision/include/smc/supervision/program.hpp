#pragma once
// The part program as the supervisor sees it: a fixed-size list of
// face-milling passes, so a rewrite (module F) never allocates. One program
// model for cell and edge: the cell plans it, the edge runs it, the drives
// consume it.

#include <array>
#include <cstdint>

namespace smc::supervision {

struct PassSpec {
  double depth_mm = 0;       // depth of this pass
  double feedrate_mm_s = 0;  // programmed feedrate
  double spindle_rpm = 0;
  double force_reference_n = 0;  // planned F_ref (N); 0: from the power limit
};

struct FixedProgram {
  static constexpr int kMaxPasses = 16;
  std::array<PassSpec, kMaxPasses> passes{};
  uint16_t count = 0;
  uint32_t revision = 0;  // bumped by every rewrite

  double total_depth_mm() const noexcept;
  // Depth removed by passes [0, i).
  double depth_before(int i) const noexcept;
};

// The most passes a program may have (planning refuses more).
inline constexpr int kMaxPasses = FixedProgram::kMaxPasses;

// Module F (chatter suppressor): rewrite the program from pass `current`
// on so that the depth those passes remove is taken in one more pass, all
// of equal depth. Returns false (program unchanged) when the program is
// full. Real-time safe.
bool add_one_pass(FixedProgram& program, int current) noexcept;

}  // namespace smc::supervision
