#pragma once
// The fixed machine and operation parameter modules (paper, design step 2)
// as the edge's modules read them, read and checked from a
// smc.config.SupervisorConfig off the loop; and the conversions between
// power, force, feed and speed that cell and edge must agree on.

#include <string>

#include "smc/common/diagnostic.hpp"

namespace smc::config {
class SupervisorConfig;
class Structure;
}  // namespace smc::config

namespace smc::supervision {

// A configuration that cannot be used. what() lists every problem, one per
// line, as "supervisor_config.<field path>: what is wrong; fix: what to do",
// e.g. "supervisor_config.operation.sample_period_s: must be > 0 (got 0);
// fix: set the force sampling period, e.g. 0.0005".
struct ConfigError : common::DiagnosticError {
  using common::DiagnosticError::DiagnosticError;
  // One problem whose text names its own place.
  explicit ConfigError(const std::string& message)
      : common::DiagnosticError(common::Diagnostic{"", message, ""}) {}
};

// Cutting speed at the cutter's periphery, m/s.
double cutting_speed_m_s(double cutter_radius_mm, double spindle_rpm) noexcept;
// F_ref = P_max / V / safety (the paper's reference force), N; 0 when V is 0.
double force_reference_n(double max_power_w, double cutter_radius_mm, double spindle_rpm,
                         double safety_factor = 1) noexcept;
// Feedrate (mm/s) for a feed per tooth at a spindle speed, and back.
double feedrate_mm_s(double feed_per_tooth_mm, int teeth, double spindle_rpm) noexcept;
double feed_per_tooth_mm(double feedrate_mm_s, int teeth, double spindle_rpm) noexcept;

// The longest revolution, in samples, the edge's revolution-rate modules
// handle (module E's buffer): 1024 is 0.5 s at 0.5 ms, 120 rpm.
inline constexpr int kMaxSamplesPerRevolution = 1024;

struct Parameters {
  // Fixed machine parameters.
  double max_spindle_power_w = 0;
  double max_feedrate_mm_s = 0;
  double max_spindle_rpm = 0;
  double min_spindle_rpm = 0;  // 0 in the message: max_spindle_rpm / 4
  // Fixed operation parameters.
  double max_feed_per_tooth_mm = 0;
  double min_feed_per_tooth_mm = 0;
  int teeth = 0;
  double cutter_radius_mm = 0;
  double sample_period_s = 0;
  double fast_period_s = 0;
  double slow_period_s = 0;
  double contact_threshold_n = 0;
  double force_reference_n = 0;  // 0: from the power limit and cutting speed
  double force_safety_factor = 1;
  double model_time_constant_s = 0;
  double adaptive_time_constant_s = 0;
  double rls_forgetting = 1;
  double adaptive_feed_exponent = 0;
  double chatter_threshold = 0;
  int chatter_confirm_revolutions = 1;
  double chatter_band_low_hz = 0;
  double chatter_band_high_hz = 0;
  double harmonic_guard_hz = 0;
  double chatter_min_rms_n = 0;
  double suppression_hold_s = 0;
  double force_sensor_range_n = 0;
  double power_time_constant_s = 0.1;           // module M's filter on the power/force ratio
  double power_target_fraction = 0.95;          // module M holds the mean power at this x P_max
  double breakage_threshold = 0.3;              // module N: drop and rise, share of the window mean
  double speed_change_frequency_margin = 0.04;  // module O: tooth frequency (1 - m) f_c / k
  double speed_change_max_ratio = 2;            // module O: within [1/r, r] x programmed
  double spindle_at_speed_tolerance = 0.01;     // module O: at speed within this share
  double speed_change_timeout_s = 5;            // module O: at speed within this time
  // Identification segment: F_ref x levels[i] for `revolutions` revolutions
  // each, in the last pass from kIdentificationSettle revolutions after
  // contact (identification_revolutions == 0: none). Each level, and 1
  // after the last, is reached by a ramp: the factor moves by at most
  // kIdentificationRamp of itself per revolution, so that the feed moves by
  // less than 5 % a revolution. Module N compares each tooth window with the
  // revolution before: a step down looks to it like a broken tooth, and a
  // step up hides one for a revolution or two.
  static constexpr int kMaxIdentificationLevels = 4;
  static constexpr int kIdentificationSettle = 20;
  static constexpr double kIdentificationRamp = 0.025;
  double identification_levels[kMaxIdentificationLevels] = {};
  int identification_level_count = 0;
  int identification_revolutions = 0;
  // Force-process model (eq. 1) for module L: F_Y[kN] = K d^beta f^alpha.
  bool has_force_model = false;
  double model_k_kn = 0;
  double model_beta = 0;
  double model_alpha = 0;
  // The cutter's arc over the part's width (milling_model.workpiece: width
  // and offset against cutter_radius_mm), radians; 0: not known. Module N
  // looks for the tooth that took a broken tooth's chip within as many
  // windows as this arc spans.
  double cut_arc_rad = 0;
  // The machine's structure in y (milling_model.structure: tool_y, then
  // part_y; both move the tool against the part under the same force), for
  // module E's estimate of the tool-part vibration from the wideband F_y
  // channel (edge/CHATTER.md). None: E judges F_z alone.
  struct VibrationMode {
    double natural_frequency_rad_s = 0;
    double damping_ratio = 0;
    double stiffness_n_per_mm = 0;
  };
  static constexpr int kMaxVibrationModes = 4;
  VibrationMode vibration_modes[kMaxVibrationModes] = {};
  int vibration_mode_count = 0;
  // The wideband F_y channel's anti-alias filter (a Butterworth of
  // vibration_sensor_order), whose attenuation module E's estimate undoes
  // (operation.wideband_cutoff_hz; 0 there: 1000 Hz, the F_z channel's;
  // operation.wideband_filter_order; 0 there: 2).
  double vibration_sensor_cutoff_hz = 1000;
  int vibration_sensor_order = 2;
  // The wideband F_y channel's noise (N rms, white after the filter), whose
  // expected share module E takes out of both energies of q
  // (operation.wideband_noise_rms_n; 0: none).
  double vibration_sensor_noise_rms_n = 0;
  // Samples of the wideband F_y channel per sample period
  // (operation.wideband_samples_per_tick; 0 there: 1): module E's estimate
  // runs at that multiple of the loop's rate.
  static constexpr int kMaxVibrationSamplesPerTick = 8;
  int vibration_samples_per_tick = 1;
  // Module E's rules on the estimated vibration's change from one revolution
  // to the next (not in the configuration message: the detector study's
  // values; the study overrides them to try others). The values below are
  // those chosen for a channel at the loop's rate; read_parameters replaces
  // them with the set chosen for a channel at kFineChannelRateHz when the
  // channel is that fast (set_vibration_rules_for_channel). Chatter when it exceeds
  // `rise` and grows, then grows again, over judged revolutions; or exceeds
  // `climb` and grows three times in a row; or exceeds `pause` and grows,
  // stays above it a revolution, then passes where it grew to (growing: by
  // more than `growth` x the revolution before); or exceeds `net` in three
  // in a row, the last more than `net_growth` x the one before them and
  // above the first of them, none below (1 - `net_dip`) x the one before
  // it; or jumps past `jump` (to more than `jump_growth` x the revolution
  // before) and stays above it the next revolution, at no less than
  // (1 - `jump_dip`) x the jump (chatter drawn onto a spindle order grows
  // for a revolution or two and then repeats itself, so that q falls back);
  // or rises three times in a row, each by more than `steep_growth`, from at
  // least `steep_from` to past `steep` (chatter from low grows fast and may
  // fall back before a second rise above `rise`), or so only to past
  // `confirmed` where F_z's non-harmonic share rose too, by more than
  // `confirmed_growth` x in each of the last two (the two channels' evidence
  // together); or exceeds `level` in three in a row; or exceeds `held` on
  // average over two judged revolutions in a row, neither below
  // `held_floor`, both with the cutter wholly in the part (the drive's
  // engagement 1 at each end of both) and off an aborted pass's ledge (on
  // with a channel from kHeldRuleChannelRateHz, 10 kHz; off, kNoHeld, below
  // it); or when the estimated
  // vibration's share at the spindle orders halfway between tooth harmonics
  // exceeds `flip` in `flip_revolutions` in a row (a period doubling, with an even number of
  // teeth, repeats every revolution: q sees it only while it grows); or, where
  // `backup` is at most 1, when F_z's non-harmonic share exceeds it in three
  // (off since 2026-11-30, kNoBackup: runout alone took S past 0.7 for
  // three revolutions in stable cuts, and to 0.85 in one, at speeds and
  // widths off the study's grid, while q and the period doubling's share
  // caught every chatter it had caught; edge/CHATTER.md, "S's backup").
  double chatter_vibration_rise = 0.22;
  double chatter_vibration_climb = 0.14;
  double chatter_vibration_pause = 0.18;
  double chatter_vibration_growth = 1.01;
  double chatter_vibration_net = 0.135;
  double chatter_vibration_net_growth = 1.5;
  double chatter_vibration_net_dip = 0.15;
  double chatter_vibration_jump = 0.25;
  double chatter_vibration_jump_growth = 1.2;
  double chatter_vibration_jump_dip = 0.3;
  double chatter_vibration_steep = 0.23;
  double chatter_vibration_steep_growth = 1.15;
  double chatter_vibration_steep_from = 0.02;
  double chatter_vibration_confirmed = 0.18;
  double chatter_vibration_confirmed_growth = 1.2;
  double chatter_vibration_level = 0.8;
  static constexpr double kNoHeld = 1e9;  // above any q: the held rule is off
  double chatter_vibration_held = kNoHeld;
  double chatter_vibration_held_floor = 0.14;
  double chatter_vibration_flip = 0.5;
  int chatter_vibration_flip_revolutions = 2;
  static constexpr double kNoBackup = 2;  // above any share: the backup is off
  double chatter_vibration_backup = kNoBackup;
  // A revolution not judged because the mean F_z rose by more than a tenth
  // beyond the engagement's rise (a step in the cut, or chatter's own
  // growth): false forgets the rules' last revolutions there, true keeps
  // them, so the rules compare across it (edge/CHATTER.md, "Judging through
  // a step in the cut"), save where the cutter crosses the ledge an aborted
  // pass left (Signals::crossing_ledge: the step is the cut's, and the
  // controller's answer to it reads as chatter).
  bool chatter_vibration_keep_across_steps = false;

  // Derived, in samples.
  int samples_per_fast = 0;
  int samples_per_revolution = 0;  // of slow_period_s: the clock while the spindle is still
  // Most and fewest samples a revolution can have within the speed range.
  int max_samples_per_revolution = 0;
  int min_samples_per_revolution = 0;
  int samples_per_hold = 0;

  // F_ref at a spindle speed: the configured reference when one is given,
  // else force_reference_n(P_max, R, rpm, safety). Real-time safe.
  double force_reference_at(double spindle_rpm) const noexcept;
  // Feedrate (mm/s) for a feed per tooth at a spindle speed, and back.
  // Real-time safe.
  double feedrate_for(double feed_per_tooth_mm, double spindle_rpm) const noexcept;
  double feed_per_tooth_for(double feedrate_mm_s, double spindle_rpm) const noexcept;
};

// The wideband F_y channel's rate (samples a second) from which module E's
// rules are those chosen for a channel that reads the vibration between the
// loop's samples, at 10 kHz (edge/CHATTER.md, "Label and channel at 10
// kHz"); below it, those chosen at the loop's 2 kHz. Measured at 4 kHz too,
// where the 10 kHz set did better than the 2 kHz set on the grid
// (0 false detections and 118 of 120 unstable cuts within 3 revolutions,
// against 1 and 112) and on the mismatched mill (edge/CHATTER.md, "What the
// channel's filter costs E"). 6 and 8 kHz were not measured.
inline constexpr double kFineChannelRateHz = 4000;
// The rate from which the held rule is on (chatter_vibration_held): 10 kHz,
// where E reads the mill's q within 1-3 %. At 4 kHz it caught one more cut
// within 3 revolutions off the study's grid and made one false detection,
// a cut whose q hovered at 0.147 before its onset (edge/CHATTER.md, "The
// held rule").
inline constexpr double kHeldRuleChannelRateHz = 10000;
// The channel's rate of `p` (vibration_samples_per_tick / sample_period_s).
double vibration_channel_rate_hz(const Parameters& p) noexcept;
// Sets module E's vibration rules to the set chosen for a channel at
// `channel_rate_hz` (above). Leaves every other parameter alone.
void set_vibration_rules_for_channel(Parameters& p, double channel_rate_hz) noexcept;

// Whether `cfg` runs module E (its modules name it) with no structure in y
// (milling_model.structure's tool_y and part_y): E then judges the force
// spectrum alone (S), far worse than through its vibration estimate
// (edge/CHATTER.md, "The structure E is given"). The cell gives such a plan
// its machine's structure at dispatch; the edge warns of one it accepts.
bool chatter_detector_without_structure(const smc::config::SupervisorConfig& cfg) noexcept;

// The wideband F_y samples a period module E takes from the drive under
// `cfg` (operation.wideband_samples_per_tick, 0 meaning 1), or 0 where E
// does not read the channel (E not run, or run with no structure in y). A
// drive that brings another count makes E fail, so the simulated mill's
// configuration and LinuxCNC's dynamometer are checked against it before
// anything moves.
unsigned wideband_samples_e_takes(const smc::config::SupervisorConfig& cfg) noexcept;

// Module E's wideband channel against the structure it undoes: the y mode
// (tool_y, part_y, as E uses them) that the channel's anti-alias filter
// takes furthest down before E undoes it. Undoing it multiplies the
// channel's noise by as much where that mode chatters, and on the detector
// study's grid a filter that took the paper's tool mode (652 Hz) 9.7 dB
// down caught far fewer onsets in time and gave false detections, where
// those that took it 6 dB or less did not (edge/CHATTER.md, "What the
// channel's filter costs E"). A mode above the channel's Nyquist frequency
// E cannot see at all.
struct WidebandModeLoss {
  double mode_hz = 0;          // the mode's natural frequency
  double loss_db = 0;          // the filter's attenuation there, 10 log10(1 + (f/fc)^2n)
  double nyquist_hz = 0;       // the channel's
  bool above_nyquist = false;  // the mode lies above it
};
// The worst mode of `p` (vibration_modes, vibration_sensor_*), or a loss of
// 0 where `p` has no mode.
WidebandModeLoss wideband_mode_loss(const Parameters& p) noexcept;
// Above this loss at a mode the channel is called out (above: measured).
inline constexpr double kWidebandModeLossWarnDb = 8;
// A sentence for the logs, `smc-edge simulate`'s stderr and the cell's
// explanation, where E reads the channel under `cfg` (wideband_samples_e_takes
// > 0) and a y mode is lost beyond kWidebandModeLossWarnDb or above the
// Nyquist frequency: what is lost, what it costs and the fix. Empty
// otherwise, and for a configuration that does not read (its own checks
// report that).
std::string wideband_channel_warning(const smc::config::SupervisorConfig& cfg);
// The same for a channel and a structure alone, as a machine's catalog
// record and a model of it give them (`smc-cell catalog apply`): the
// channel's rate (Hz), its filter's cut-off (Hz) and order, and the
// structure's y modes (the first kMaxVibrationModes, as E uses them).
// Empty where the structure has no y mode or the channel is no channel.
std::string wideband_channel_warning(double rate_hz, double cutoff_hz, int filter_order,
                                     const smc::config::Structure& structure);

// Reads and checks every field the modules use, collecting every problem in
// `problems` (field paths under "supervisor_config."). The result is only
// meaningful when no problem was added.
Parameters read_parameters(const smc::config::SupervisorConfig& cfg, common::Diagnostics& problems);
// The same, throwing ConfigError with every problem.
Parameters parameters_from_config(const smc::config::SupervisorConfig& cfg);

}  // namespace smc::supervision
