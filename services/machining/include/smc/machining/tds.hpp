#pragma once
// Batch time-domain simulation at constant conditions, its stability verdict,
// and the paper's chatter analysis: the marginally stable depth at a spindle
// speed, by bisection over depth with time-domain runs (Appendix, last
// paragraph).
//
// A batch run integrates the same model as MillSimulator, with the internal
// step shrunk so that a whole number of steps makes one tooth period: the
// discrete system is then exactly periodic, and its chatter-free motion is a
// periodic orbit that can be computed directly (on it the chip is the nominal
// one, so the motion is the structure's steady response to the nominal
// forces).
//
// Stability criterion (README.md, "Stability criterion"): the cut starts on
// that periodic motion, every mode's displacement disturbed by 1e-5 of the
// feed per tooth; the full nonlinear model is then integrated and the
// deviation of the modal state from the periodic motion sampled once per
// tooth period (a Poincare section):
//   - stable   once the deviation has decayed by 1e6 from its largest value,
//   - unstable once it has grown by 1e4 from the disturbance,
//   - otherwise, at the end of the run, from the largest eigenvalue magnitude
//     rho of the linear map fitted to the last samples (dynamic mode
//     decomposition): stable iff rho < 1.
// rho estimates the dominant Floquet multiplier of the periodic cut, so the
// verdict changes where the semi-discretization (lobes.hpp) puts the
// boundary; the disturbance is small enough that the run stays in the linear
// range until the verdict is clear.
//
// Runs that start from rest (the default of simulate(), which shows a cut as
// a machine would start it) are judged less strictly from the change of the
// once-per-period state D_k: settled when D_k fell below 1e-9 of its maximum;
// otherwise unstable if teeth jumped out of the cut mid-engagement in the
// last quarter or D grew over the second half.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "smc/machining/model.hpp"

namespace smc::machining {

struct BatchOptions {
  double duration_s = 0.5;
  // Internal step upper bound (s); 0: the model's internal_step_s. The step
  // used is tooth period / ceil(tooth period / bound).
  double max_internal_step_s = 0;
  // true: the cutter is in the part from t = 0 and the part never ends (a
  // steady cut, for stability). false: the cutter starts at start_position_mm
  // and travels along a part of the model's length.
  bool steady = true;
  double start_position_mm = 0;
  // Feedrate for a travelling run is feed_per_tooth x teeth x rev/s.
  // Record every `record_every_s` (0: nothing recorded). Records are instantaneous
  // values at the recording instants.
  double record_every_s = 0.5e-3;
  // Start on the cut's chatter-free periodic motion, every mode's
  // displacement disturbed by disturbance_mm, instead of from rest. Only with
  // steady = true.
  bool start_on_steady_cut = false;
  double disturbance_mm = 0;
  // Stop as soon as the verdict is certain (settled, or saturated chatter).
  bool stop_when_decided = false;
};

enum class Verdict : std::uint8_t { stable, unstable };

struct StabilityReport {
  Verdict verdict = Verdict::stable;
  // Estimated dominant Floquet multiplier magnitude (growth of a disturbance
  // per tooth period) and its logarithm; NaN when the run was decided before
  // an estimate was needed (decayed or grew past the thresholds).
  double multiplier = 0;
  double growth_per_period = 0;
  bool settled = false;           // the disturbance (or D_k) died out
  bool grew = false;              // the disturbance grew by 1e4
  bool teeth_jumped_out = false;  // a tooth left the cut mid-engagement late in the run
  int periods = 0;                // tooth periods simulated
  std::string reason;             // one line, for people
};

struct BatchResult {
  double internal_step_s = 0;
  int steps_per_tooth_period = 0;
  // Records (see BatchOptions::record_every_s).
  std::vector<double> time_s;
  std::vector<double> fx_n, fy_n, fz_n;
  std::vector<double> power_w;
  std::vector<double> tool_x_mm, tool_y_mm, part_x_mm, part_y_mm;
  std::vector<double> tool_position_mm;
  std::vector<int> teeth_in_cut;
  // Poincare section, once per tooth period: the norm of the modal state's
  // deviation from the periodic motion (start_on_steady_cut) or of its change
  // over the period D_k (start from rest); mm.
  std::vector<double> section;
  StabilityReport stability;
  double mean_power_w = 0;  // over the whole run
  double max_abs_fy_n = 0;
};

// Runs one cut. Throws ModelError / std::invalid_argument for a bad model,
// cut or option.
BatchResult simulate(const MillingModel& model, const CutConditions& cut,
                     const BatchOptions& options = {});

// Only the verdict, by the criterion above (start on the periodic motion, no
// records, stops as soon as it is certain): what the critical-depth search
// calls. tooth_periods: the longest run.
StabilityReport assess_stability(const MillingModel& model, const CutConditions& cut,
                                 int tooth_periods = 160, double max_internal_step_s = 0);

struct DepthProbe {
  double depth_mm = 0;
  bool stable = false;
  double growth_per_period = 0;
};

struct TdsSearchOptions {
  double initial_depth_mm = 1.0;     // first probe; the bracket grows or shrinks from it
  double max_depth_mm = 50;          // search no deeper (result: stable up to here)
  double min_depth_mm = 1e-3;        // no shallower (result: unstable down to here)
  double relative_tolerance = 1e-3;  // bracket width / depth at which bisection stops
  int tooth_periods = 160;           // longest run per probe
  double max_internal_step_s = 0;    // 0: the model's internal_step_s
  // Called after each probe (for progress output); may be empty.
  std::function<void(const DepthProbe&)> on_probe;
};

struct TdsSearchResult {
  // Midpoint of the final bracket [stable_depth_mm, unstable_depth_mm].
  double critical_depth_mm = 0;
  double stable_depth_mm = 0;    // deepest probe found stable
  double unstable_depth_mm = 0;  // shallowest probe found unstable
  bool bounded = false;          // false: stable at max_depth_mm (or unstable at min_depth_mm)
  std::vector<DepthProbe> probes;
};

// The marginally stable depth at a spindle speed and feed per tooth. Throws
// for a bad model or arguments.
TdsSearchResult critical_depth_tds(const MillingModel& model, double spindle_rpm,
                                   double feed_per_tooth_mm, const TdsSearchOptions& options = {});

}  // namespace smc::machining
