#pragma once
// The stepping time-domain simulator: the core of the edge's simulated mill.
//
// The mill calls step() once per force sample (0.5 ms by default) with the
// feedrate, spindle speed and depth of that sample; all three may change from
// one call to the next, and the feedrate may be 0 (feed hold: the cutter
// keeps turning in place). Inside, the model is integrated at a fixed
// internal step (the model's internal_step_s, shrunk so that a whole number
// of steps makes one sample) with
//   - tooth angles advancing with the spindle speed,
//   - the cutter's axis advancing along the feed (tool_position_mm, +x) by
//     feedrate x time, so that a tooth cuts only where its tip is over
//     material not yet removed in this pass: on the leading half of the
//     cutter (cos theta > 0), inside the part's width band and inside the
//     part's length [0, length_mm],
//   - the regenerative chip (README.md, "Chip thickness"), with the
//     relative tool-part displacement one delay earlier read from a history
//     buffer sized at construction for the lowest spindle speed,
//   - the structure's modes stepped exactly (structure.hpp).
//
// A caller that filters the force itself passes a StepForceTrace and gets
// the force of every internal step as well.
//
// Real-time contract: the constructor allocates and may throw; step(),
// set_tool_position(), reset() and the accessors never allocate, lock or
// throw. Results are deterministic: the same calls give the same samples.

#include <cstdint>
#include <memory>

#include "smc/machining/model.hpp"

namespace smc::machining {

struct SimulatorOptions {
  double sample_period_s = 0.5e-3;  // one step() call
  // Lowest spindle speed the history buffer is sized for (the delay is
  // longest at the lowest speed; the buffer is rounded up to a power of two).
  // A slower spindle still runs: when its delay exceeds the buffer, the delay
  // is clamped to it and StepStatus::kBelowMinSpindle is set.
  double min_spindle_rpm = 100;
  // Internal step upper bound (s); 0: the model's internal_step_s.
  double max_internal_step_s = 0;
  // Cutter axis position along the feed at construction and reset() (mm).
  double initial_tool_position_mm = 0;
  // true: Sample's forces and power are the values at the sample instant.
  // false: those of the last internal step (the force held over it,
  // evaluated at its middle), which saves one force evaluation per call:
  // for callers that filter the force themselves (see StepForceTrace).
  bool forces_at_sample_instant = true;
  // false: every chip is the nominal one, the vibration's marks on the
  // surface never cut again: a mill on which chatter cannot start, whose
  // vibration is the forced response alone (the chatter detector study's
  // --no-regeneration tells the two apart with it).
  bool regenerative = true;
};

// What the mill commands for one sample.
struct SampleInput {
  double feedrate_mm_s = 0;  // >= 0; 0 = feed hold
  double spindle_rpm = 0;    // >= 0; 0 = spindle stopped (no cutting)
  double depth_mm = 0;       // >= 0
};

// Status bits of one step() (0 = all well).
struct StepStatus {
  // An input was NaN, infinite or negative: the sample ran with the cutter
  // out of the material and not moving (the structure rings down).
  static constexpr std::uint32_t kInvalidInput = 1u << 0;
  // Spindle slower than SimulatorOptions::min_spindle_rpm: the regenerative
  // delay was clamped to the history buffer.
  static constexpr std::uint32_t kBelowMinSpindle = 1u << 1;
  // Feeding with the spindle stopped while the cutter overlaps the part.
  static constexpr std::uint32_t kSpindleStoppedInCut = 1u << 2;
  // The state became non-finite; the simulator was reset to rest.
  static constexpr std::uint32_t kNotFinite = 1u << 3;
};

// One sample's outputs. Forces act on the tool (the dynamometer under the
// part reads the opposite); the instantaneous values are those at the sample
// instant (the end of the sample period), which is what a sampled sensor sees.
struct Sample {
  double time_s = 0;  // at the end of this sample
  double fx_n = 0;
  double fy_n = 0;
  double fz_n = 0;                      // > 0 pushes the tool up, away from the part
  double power_w = 0;                   // spindle (cutting) power at the sample instant
  double mean_power_w = 0;              // averaged over the sample period
  double max_abs_fy_n = 0;              // largest |F_y| over the internal steps of the sample
  double tool_x_mm = 0, tool_y_mm = 0;  // displacements at the sample instant
  double part_x_mm = 0, part_y_mm = 0;
  double tool_position_mm = 0;  // cutter axis along the feed, end of sample
  double feed_per_tooth_mm = 0;
  int teeth_in_cut = 0;  // teeth cutting a chip at the sample instant
  std::uint32_t status = 0;
};

// Where step() puts the force of each internal step of the sample (the force
// held over the step, evaluated at its middle): arrays of steps_per_sample()
// values each, owned by the caller. For callers that filter the force
// themselves, e.g. a sensor's anti-aliasing filter running at the internal
// step: one call per sample then does what one call per internal step did,
// without paying the per-call work at every step. `vibration_y_mm`, when
// given, gets the relative tool-part vibration in y at the end of each
// step (as Sample's tool_y_mm - part_y_mm at the last): the detector
// study's label reads the vibration faster than the loop with it.
struct StepForceTrace {
  double* fx_n = nullptr;
  double* fy_n = nullptr;
  double* fz_n = nullptr;
  double* vibration_y_mm = nullptr;
};

class MillSimulator {
 public:
  // Validates the model and options (throws ModelError / std::invalid_argument)
  // and allocates everything step() needs.
  explicit MillSimulator(const MillingModel& model, const SimulatorOptions& options = {});
  ~MillSimulator();
  MillSimulator(MillSimulator&&) noexcept;
  MillSimulator& operator=(MillSimulator&&) noexcept;
  MillSimulator(const MillSimulator&) = delete;
  MillSimulator& operator=(const MillSimulator&) = delete;

  // Real-time safe. Advances one sample period; returns out.status.
  std::uint32_t step(const SampleInput& input, Sample& out) noexcept;
  // The same, and writes the force of every internal step into trace (each
  // array must hold steps_per_sample() values).
  std::uint32_t step(const SampleInput& input, Sample& out, const StepForceTrace& trace) noexcept;

  // Real-time safe. Moves the cutter axis to x (mm) along the feed, e.g. at
  // the start of a pass (x = -radius - approach puts the cutter in air
  // before the part). A non-finite x is ignored.
  void set_tool_position(double x_mm) noexcept;
  double tool_position_mm() const noexcept;
  // Real-time safe. Tool condition from now on: tooth `tooth` (0-based)'s
  // radial runout (a break moves its edge back: runout minus the edge lost,
  // and the next tooth takes the chip it no longer cuts), and every cutting
  // pressure times `scale` (wear). reset() keeps them: a new part does not
  // mend the tool.
  void set_tooth_runout_mm(int tooth, double runout_mm) noexcept;
  double tooth_runout_mm(int tooth) const noexcept;
  void set_force_scale(double scale) noexcept;
  // Real-time safe. Structure at rest, history cleared, time and spindle
  // angle to 0, tool at the initial position.
  void reset() noexcept;

  double time_s() const noexcept;
  double internal_step_s() const noexcept;
  int steps_per_sample() const noexcept;
  double sample_period_s() const noexcept;
  const MillingModel& model() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::machining
