#pragma once
// The drive interface: what the edge needs of a machine. The simulated mill
// (sim_mill.hpp) and the replay drive (replay_drive.hpp) implement it; a real
// machine's I/O would too.
//
// Real-time contract: step() and rewrite() run in the loop and never
// allocate, lock, log or throw. load() runs before the loop.

#include "smc/edge/program.hpp"
#include "smc/edge/types.hpp"

namespace smc::edge {

struct DriveSample {
  ForceSample force;  // at the end of the sample period
  double spindle_rpm = 0;
  double depth_mm = 0;  // depth of the pass in progress
  double programmed_feedrate_mm_s = 0;
  double feedrate_mm_s = 0;                    // actually applied
  double x_mm = 0;                             // tool position along the feed
  double spindle_power_w = __builtin_nan("");  // NaN when the drive cannot tell
  // Relative tool-part vibration in y (mm), when the drive knows it (the
  // simulated mill does, and LinuxCNC with the virtual dynamometer; a real
  // machine would need an extra sensor): NaN otherwise. Used only to find
  // chatter onset as ground truth in studies and run summaries.
  double vibration_y_mm = __builtin_nan("");
  // The same vibration at the wideband channel's instants where that
  // channel samples faster than the loop (the simulated mill only):
  // `vibration_count` values, evenly spaced, oldest first, the last being
  // vibration_y_mm. 0: at the sample period alone. The detector study's
  // label reads the vibration at the rate module E reads its channel.
  int vibration_count = 0;
  double vibration_y_sub_mm[ForceSample::kMaxWideSamples] = {};
  // Share of the full-width engagement arc in cut (0 in air, 1 when the
  // cutter is fully in the part); NaN when the drive cannot tell.
  double engagement = __builtin_nan("");
  int pass_index = 0;    // index into the program
  bool in_pass = false;  // cutting a pass (not repositioning, not done)
  bool program_done = false;
};

class Drive {
 public:
  virtual ~Drive() = default;
  // Not real-time: take a program and stand at the start of its first pass.
  virtual void load(const FixedProgram& program) = 0;
  // Real-time: apply the feedrate command for one sample period; fill `out`
  // with the state at its end.
  virtual Status step(double feedrate_cmd_mm_s, DriveSample& out) noexcept = 0;
  // Real-time: the program was rewritten from pass `from` on (chatter
  // suppressor). The pass in progress is abandoned; the tool goes back to
  // the start and continues with pass `from` of the new program.
  virtual Status rewrite(const FixedProgram& program, int from) noexcept = 0;
  virtual double sample_period_s() const noexcept = 0;
  // Whether change_spindle_speed() works on this drive (module O needs it).
  virtual bool can_change_spindle_speed() const noexcept { return false; }
  // Real-time: turn the spindle at `rpm` from now on, for the rest of the
  // program (a spindle speed override on a CNC); the speed the spindle
  // reaches shows in DriveSample::spindle_rpm.
  virtual Status change_spindle_speed(double /*rpm*/) noexcept { return Status::kError; }
  // Whether retract() works on this drive (after a tool breakage).
  virtual bool can_retract() const noexcept { return false; }
  // Real-time: lift the tool clear of the part where it stands (the feed is
  // held); it stays there until the program is loaded again.
  virtual Status retract() noexcept { return Status::kError; }
};

}  // namespace smc::edge
