#pragma once
// The loop's shared signals ("blackboard"): every module reads what it needs
// and writes its outputs here. Owned by the edge core, preallocated, plain
// data; only the loop thread touches it.
//
// Module outputs are grouped; each group has one owner, the module that
// declares it in Module::writes(). The core refuses a configuration in which
// two configured modules declare the same group, and (when asked to check,
// as the tests do) faults a module that changes a group it did not declare.

#include <cstdint>

#include "smc/edge/types.hpp"

namespace smc::edge {

// Groups of module outputs, one bit each (the fields they cover are listed
// in Signals below).
enum class Signal : uint32_t {
  kOperatorRequests = 1u << 0,  // B: feed_hold_requested, operator_chatter_event
  kChatterSignalled = 1u << 1,  // D: chatter_signalled
  kForcePeak = 1u << 2,         // I: f_y_peak_n, revolutions, f_y_updated
  kContact = 1u << 3,           // J: contact
  kChatterDetected = 1u << 4,   // E: chatter_detected, chatter_ratio, chatter_frequency_hz,
                                //    chatter_vibration_ratio, chatter_vibration_flip
  kSuppression = 1u << 5,       // G: rewrite_requests, suppression_hold, suppression_done
  kProgramRewritten = 1u << 6,  // F: program_rewritten
  kGainEstimate = 1u << 7,      // H: gain_estimate, gain_valid
  kControllerFeed = 1u << 8,    // K or L: controller_feed_per_tooth_mm, controller_valid
  kFeedCommand = 1u << 9,       // A: feedrate_cmd_mm_s, feed_per_tooth_cmd_mm, feed_limited
  kPowerLimit = 1u << 10,       // M: power_mean_w, power_estimated, force_reference_scale
  kToolBreakage = 1u << 11,     // N: tool_broken, breakage_window, breakage_drop
  kSpeedChange = 1u << 12,      // O: spindle_speed_cmd_rpm, speed_change_done
};
using SignalMask = uint32_t;
constexpr SignalMask operator|(Signal a, Signal b) noexcept {
  return static_cast<SignalMask>(a) | static_cast<SignalMask>(b);
}
constexpr SignalMask operator|(SignalMask a, Signal b) noexcept {
  return a | static_cast<SignalMask>(b);
}
constexpr SignalMask mask(Signal s) noexcept { return static_cast<SignalMask>(s); }
// "feed_command", … for messages; "" for a mask of several bits or none.
const char* signal_name(Signal s) noexcept;

struct Signals {
  // --- written by the core before the modules run
  ForceSample sample;              // this tick's sensor sample
  OperatorInputs operator_inputs;  // latest operator inputs
  ModuleMask active = 0;           // modules the operation supervisor enables
  double spindle_rpm = 0;          // current pass
  double depth_mm = 0;             // current pass depth
  double programmed_feedrate_mm_s = 0;
  double force_reference_n = 0;          // F_ref now: the pass's base x M's scale
  double force_reference_base_n = 0;     // the pass's planned F_ref, else P_max / V
  bool force_reference_planned = false;  // the base is the pass's planned F_ref
  double spindle_power_w = 0;            // from the drive; NaN when it cannot tell
  bool in_pass = false;                  // the drive is executing a pass (not repositioning)
  // The revolution that ended at this tick, from the core's revolution clock
  // (the measured spindle speed): its samples and duration. Revolution-rate
  // modules read them; between revolution ticks they keep the last values.
  int revolution_samples = 0;
  double revolution_period_s = 0;
  // Where this sample lies in the core's revolution, in [0, 1): the phase at
  // its start (a per-tooth module splits the revolution into tooth windows).
  double revolution_phase = 0;
  // The spindle speed was changed (module O) in the pass in progress:
  // receptivity h (at most one speed change per pass).
  bool speed_changed_in_pass = false;
  // Share of the cutter's engagement arc in the part (the drive's, from the
  // path and the part's edges); NaN when the drive cannot tell.
  double engagement = __builtin_nan("");
  // The cutter is crossing the ledge an aborted pass left in this pass's
  // depth (the core's record of the rewrites, and the drive's position): a
  // step in the force there is the cut's own.
  bool crossing_ledge = false;

  // --- B operator input monitor
  bool feed_hold_requested = false;     // receptivity a
  bool operator_chatter_event = false;  // a new chatter signal this fast period
  // --- D operator chatter detector
  bool chatter_signalled = false;  // receptivity c (one fast period long)
  // --- I force signal processor
  double f_y_peak_n = 0;     // F_Y = max |F_y| over the last revolution (held when off)
  uint32_t revolutions = 0;  // number of F_Y values produced
  bool f_y_updated = false;  // I produced a new F_Y in this tick
  // --- J contact monitor
  bool contact = false;  // receptivity b
  // --- E automatic chatter detector
  bool chatter_detected = false;    // receptivity d (latched until E is reset)
  double chatter_ratio = 0;         // non-harmonic / total F_z energy, last revolution
  double chatter_frequency_hz = 0;  // strongest non-harmonic component
  // The estimated vibration's change from the revolution before over its
  // RMS, last revolution (0: not judged, or no estimate)
  double chatter_vibration_ratio = 0;
  // The estimated vibration's share at the spindle orders halfway between
  // tooth harmonics (a period doubling), last judged revolution (0: none)
  double chatter_vibration_flip = 0;
  // --- G chatter suppression routine (with F)
  uint32_t rewrite_requests = 0;   // G: requests to run F so far (F serves each once)
  bool suppression_hold = false;   // G holds the feed
  bool suppression_done = false;   // receptivity e
  bool program_rewritten = false;  // F rewrote the program this tick
  // --- H parameter estimator
  double gain_estimate = 0;  // theta = K d^beta in N / (mm/tooth)^alpha
  bool gain_valid = false;
  // --- K / L force controllers
  double controller_feed_per_tooth_mm = 0;
  bool controller_valid = false;
  // --- M spindle power monitor
  double power_mean_w = 0;           // mean spindle power over the last revolution
  bool power_estimated = false;      // from the forces (the drive gives no power)
  double force_reference_scale = 1;  // F_ref = base x this, in (0, 1]
  // --- N tool-breakage detector
  bool tool_broken = false;  // receptivity f (latched until N is reset)
  int breakage_window = -1;  // the tooth window that lost its chip (0-based, in revolution order)
  double breakage_drop = 0;  // its fall, as a share of the mean window force
  // --- O spindle-speed chatter suppressor
  double spindle_speed_cmd_rpm = 0;  // the speed O commands (0: none); the core passes it on
  bool speed_change_done = false;    // receptivity g: at the new speed
  // --- A feedrate routine
  double feedrate_cmd_mm_s = 0;  // what the drive is told
  double feed_per_tooth_cmd_mm = 0;
  bool feed_limited = false;  // a limit clamped the command this period
};

// The output groups whose fields differ between `before` and `after`.
// Real-time safe (compares fields; no allocation).
SignalMask changed_signals(const Signals& before, const Signals& after) noexcept;

}  // namespace smc::edge
