#pragma once
// The supervisory modules of the paper's Table 1. Each is a plain object stepped
// by the edge core; see module.hpp for the real-time contract.

#include <array>
#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

#include "smc/edge/fractional_delay.hpp"
#include "smc/edge/module.hpp"
#include "smc/edge/program.hpp"

namespace smc::edge {

// A: programmed feedrate; zero under a feed hold (C) or the suppression
// routine's hold (G); the active force controller's feed otherwise. Always
// clamped to the machine's max feedrate and the operation's max feed/tooth.
class FeedrateRoutine final : public Module {
 public:
  FeedrateRoutine() noexcept : Module(ModuleId::A) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kFeedCommand); }
  bool after_supervisor() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override {}
  Status update(Signals& s) noexcept override;

 private:
  EdgeParameters p_;
};

// B: has the operator requested a feed hold (a) or signalled chatter?
class OperatorInputMonitor final : public Module {
 public:
  OperatorInputMonitor() noexcept : Module(ModuleId::B) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kOperatorRequests); }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override {
    seen_chatter_signals_ = 0;
    primed_ = false;
  }
  Status update(Signals& s) noexcept override;

 private:
  uint32_t seen_chatter_signals_ = 0;
  bool primed_ = false;
};

// C: hold the axes at a constant position. Its activity is the hold; the
// feedrate routine reads it.
class FeedHold final : public Module {
 public:
  FeedHold() noexcept : Module(ModuleId::C) {}
  Period period() const noexcept override { return Period::kEvent; }
  SignalMask writes() const noexcept override { return 0; }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override {}
  Status update(Signals&) noexcept override { return Status::kOk; }
};

// D: chatter signalled from the operator's keyboard (c), for one fast period.
class OperatorChatterDetector final : public Module {
 public:
  OperatorChatterDetector() noexcept : Module(ModuleId::D) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kChatterSignalled); }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override {}
  void clear_outputs(Signals& s) noexcept override { s.chatter_signalled = false; }
  Status update(Signals& s) noexcept override;
};

// E: automatic chatter detector. Collects the F_z samples of one spindle
// revolution, as long as the core's revolution clock (the measured spindle
// speed) makes it, and computes their spectrum (Eigen's FFT). Chatter energy is the
// energy in the search band outside a guard band around each tooth-passing
// harmonic; the statistic S is its share of the total AC energy. A
// revolution whose mean F_z moved by more than a tenth, or while the drive's
// engagement is below the most it reached since it last rose (the cutter
// leaving the part; NaN: unknown, judged), is not judged on S.
//
// Where the sensor has a wideband F_y channel (ForceSample::f_y_wide_n) and
// the configuration the machine's y modes, E also estimates the tool-part
// vibration v from it, sample by sample, through those modes, and judges
// q = RMS(v_k - v_{k-1}) / RMS(v_k) over each revolution, the revolution
// before taken at the same spindle angle (between samples, a band-limited
// fractional delay: fractional_delay.hpp):
// runout repeats and cancels, and the structure smooths the entry's edges
// out of v. Both energies are summed bin by bin over the revolution's
// spectrum, each bin corrected for what holding the force over a sample
// period and the channel's anti-alias filter take from it
// (vibration_correction), so that q is the structure's own. q is not judged
// while the cutter leaves the part, across a gap in the channel, or across
// a step in the cut (the mean F_z rising more than a tenth beyond the
// engagement's rise; across such a step the rules keep their history, or
// forget it where Parameters::chatter_vibration_keep_across_steps is off
// or the cutter crosses an aborted pass's ledge, Signals::crossing_ledge).
// d is then set by the rules of
// Parameters::chatter_vibration_* (q rising past `rise`, or past `climb`
// for longer, or past `pause` with a revolution's pause, or above `net`
// three times while growing by half, or jumping past `jump` and held there
// a revolution; q above `level`; q above `held` over two revolutions with
// the cutter wholly in the part; the estimate's share at the spindle
// orders halfway between tooth harmonics, a period doubling, above `flip`;
// or S above `backup`, where it is on), both energies less the channel's expected noise
// (Parameters::vibration_sensor_noise_rms_n); without the channel,
// by S above `chatter_threshold` in `chatter_confirm_revolutions`
// consecutive judged revolutions. It stays set until reset.
class AutomaticChatterDetector final : public Module {
 public:
  AutomaticChatterDetector();
  ~AutomaticChatterDetector() override;
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kChatterDetected); }
  bool takes_samples() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override {
    s.chatter_detected = false;
    s.chatter_ratio = 0;
    s.chatter_frequency_hz = 0;
    s.chatter_vibration_ratio = 0;
    s.chatter_vibration_flip = 0;
  }
  Status on_sample(Signals& s) noexcept override;
  Status update(Signals& s) noexcept override;

  // q for the revolution that ended with the last sample, `samples` sample
  // periods long, against the one before at `period_samples` (the measured
  // speed's revolution in sample periods; the estimate reads the channel's
  // own samples, per_tick_ of them a period), both energies less the channel's expected noise
  // (a change below it reads 0); NaN when the estimate does not cover both,
  // or the noise's share is all of the energy. Real-time safe after
  // configure(). It also reads the revolution's period-doubling share
  // (last_flip_, below).
  double vibration_ratio(int samples, double period_samples) noexcept;

  // The factor that takes a bin of the estimate's energy at this frequency
  // to the structure's: |H(j omega)|^2 / (|H_held(e^(j omega T))|^2 |L(j omega)|^2),
  // H the y modes, H_held their discretisation with the force held over a
  // sample period of the wideband channel, L the wideband channel's anti-alias filter; at most
  // kMaxCorrection. `held_norm`, when given, receives |H_held|^2 (white
  // noise on the channel reaches the estimate through it). Real-time safe.
  double vibration_correction(double frequency_hz, double* held_norm = nullptr) const noexcept;

  // The statistic for the first `samples` samples of the buffer: one
  // revolution (also used by tests and the detector study). 0 for a count
  // outside the machine's speed range. Real-time safe after configure().
  double statistic(int samples, double spindle_rpm, double* frequency_hz) noexcept;

 private:
  struct Fft;
  EdgeParameters p_;
  std::unique_ptr<Fft> fft_;
  std::vector<double> buffer_;
  std::vector<std::complex<double>> spectrum_;
  int filled_ = 0;
  int above_ = 0;
  double last_mean_ = 0, previous_mean_ = 0;
  double last_engagement_ = 0;  // the drive's, at the last revolution (NaN: unknown)
  double most_engaged_ = 0;     // and the most it reached since it last rose
  static constexpr double kMaxMeanChange = 0.1;
  static constexpr int kVibrationConfirm = 3;  // `level` and `backup`: revolutions in a row
  // The drive's engagement that counts as the cutter wholly in the part
  // (`held`): the detector study's labelling reads 1 there to 0.1 %.
  static constexpr double kWholeEngagement = 0.999;

  // The vibration estimate: per y mode its exact zero-order-hold
  // discretisation at the wideband channel's sample period and its state
  // (displacement q in mm, velocity w), driven by the wideband F_y; their
  // sum, the estimate, kept in a ring of two revolutions and a little more.
  // The channel brings per_tick_ samples a sample period
  // (Parameters::vibration_samples_per_tick), channel_period_s_ apart.
  int per_tick_ = 1;
  double channel_period_s_ = 0;
  // Why the channel was refused, with both counts: written once, the first
  // time (the fault hold reports the first cause, and the event that
  // carries this text may still be read), cleared by configure().
  std::array<char, 112> channel_error_{};
  void channel_mismatch_reason(int brought) noexcept;
  struct VibrationMode {
    double p11 = 1, p12 = 0, p21 = 0, p22 = 1, g1 = 0, g2 = 0;
    double q = 0, w = 0;
  };
  std::array<VibrationMode, EdgeParameters::kMaxVibrationModes> modes_{};
  int mode_count_ = 0;
  std::vector<double> vibration_;                         // the ring
  std::vector<double> vibration_buffer_;                  // one revolution, for its FFT
  std::vector<std::complex<double>> vibration_spectrum_;  // the change's bins, then v's
  FractionalDelay delay_;           // the revolution before, at the same spindle angle
  std::vector<double> delay_gain_;  // its power gain per bin (for the noise)
  size_t delay_gain_n_ = 0;         // for revolutions of this size,
  double delay_gain_u_ = -1;        // this point between samples
  int delay_gain_half_ = 0;         // and this many taps
  // The period doubling's orders, each read by its own Fourier sum: per
  // order its 2 cos(omega T) and Goertzel's two states.
  std::vector<double> order_twice_cos_, order_s1_, order_s2_;
  static constexpr double kMaxCorrection = 25;
  uint64_t vibration_at_ = 0;        // samples written to it
  uint64_t vibration_run_ = 0;       // of which the last ones in an unbroken run
  bool wide_channel_ = false;        // a finite wideband F_y since the last revolution
  double q1_ = 0, q2_ = 0, q3_ = 0;  // q of the last three judged revolutions (NaN: none)
  double s1_ = 0, s2_ = 0;           // S of the last two of them (NaN: none, or S not judged)
  int q_above_ = 0;                  // judged revolutions in a row with q above `level`
  bool whole1_ = false;  // the last judged revolution was cut with the cutter wholly in the part
  int flip_above_ = 0;   // and with the period doubling's share above `flip`
  // Of the revolution vibration_ratio() last read: the estimate's share of
  // its AC energy at the spindle orders halfway between tooth harmonics (a
  // period doubling; 0 with an odd number of teeth, or none read), the
  // channel's expected noise taken out of it.
  double last_flip_ = 0;
};

// G: chatter suppression routine: run F (the core rewrites the program),
// then hold the feed for `suppression_hold_s`; then e.
class ChatterSuppressionRoutine final : public Module {
 public:
  ChatterSuppressionRoutine() noexcept : Module(ModuleId::G) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kSuppression); }
  bool resets_on_activation() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override { p_ = p; }
  void reset() noexcept override {
    started_ = false;
    elapsed_fast_ = 0;
  }
  void clear_outputs(Signals& s) noexcept override {
    s.suppression_hold = false;
    s.suppression_done = false;
  }
  Status update(Signals& s) noexcept override;

 private:
  EdgeParameters p_;
  bool started_ = false;
  int elapsed_fast_ = 0;
};

// H: recursive least squares with exponential forgetting of the feed-force
// process gain theta = K d^beta in F_Y = theta f^alpha (alpha a parameter).
class ParameterEstimator final : public Module {
 public:
  ParameterEstimator() noexcept : Module(ModuleId::H) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kGainEstimate); }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override { s.gain_valid = false; }
  Status update(Signals& s) noexcept override;

 private:
  EdgeParameters p_;
  double theta_ = 0;
  double covariance_ = 0;
  bool initialised_ = false;
};

// I: F_Y = max |F_y| over one spindle revolution.
class ForceSignalProcessor final : public Module {
 public:
  ForceSignalProcessor() noexcept : Module(ModuleId::I) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kForcePeak); }
  bool takes_samples() const noexcept override { return true; }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override { peak_ = 0; }
  Status on_sample(Signals& s) noexcept override;
  Status update(Signals& s) noexcept override;

 private:
  double peak_ = 0;
};

// J: contact when F_Y exceeds the threshold (50 N), until a revolution cut
// at a feed throughout has F_Y below kRelease x the threshold.
class ContactMonitor final : public Module {
 public:
  ContactMonitor() noexcept : Module(ModuleId::J) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kContact); }
  bool takes_samples() const noexcept override { return true; }
  // Its first revolution after activation is partial: reset then.
  bool resets_on_activation() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override { threshold_ = p.contact_threshold_n; }
  void reset() noexcept override { held_ = true; }
  // Notes a revolution in which the feed was held in the pass (J was not
  // active for part of it, or the feed was zero): its low F_Y says nothing
  // about the tool having left the part.
  Status on_sample(Signals& s) noexcept override {
    held_ = held_ || (s.in_pass && !(s.feedrate_cmd_mm_s > 0));
    return Status::kOk;
  }
  Status update(Signals& s) noexcept override;

 private:
  static constexpr double kRelease = 0.75;  // x threshold: contact released below
  double threshold_ = 0;
  bool held_ = true;  // the first revolution after activation is partial
};

// M: spindle power monitor (beyond Table 1). The paper's F_ref = P_max / V
// assumes F_Y bounds the tangential force; with two teeth in the cut it
// does not, and the mean spindle power per revolution exceeds P_max. M
// measures, per revolution in contact, the mean spindle power P (the
// drive's, or V x |F_xy| when the drive has none: an upper bound with one
// tooth in the cut) and the ratio rho = P / (V F_Y) of the cut: a property
// of the engagement, nearly independent of the feed. Filtered,
//   rho(k+1) = rho(k) + g (P(k) / (V F_Y(k)) - rho(k)), g = 1 - exp(-T / tau_p),
// it gives the F_ref that puts the mean power at the target,
//   F_ref = min(base, target_fraction x P_max / safety / (V rho)),
// base being the pass's planned F_ref (SMC I: from the models) or P_max / V.
// The force controllers (K, L) read it from the next tick on. No integrator:
// rho does not depend on F_ref, so the loop inside the force loop cannot
// fight it. Runs under the state supervisor whenever configured.
class SpindlePowerMonitor final : public Module {
 public:
  SpindlePowerMonitor() noexcept : Module(ModuleId::M) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kPowerLimit); }
  bool takes_samples() const noexcept override { return true; }
  bool supervisory() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override {
    s.power_mean_w = 0;
    s.power_estimated = false;
    s.force_reference_scale = 1;
  }
  Status on_sample(Signals& s) noexcept override;
  Status update(Signals& s) noexcept override;

  static constexpr double kMinScale = 0.2;
  static constexpr double kLeadRevolutions = 2;

 private:
  EdgeParameters p_;
  double sum_w_ = 0;
  int samples_ = 0;
  bool estimated_ = false;
  double rho_ = 0;    // filtered P / (V F_Y); 0: not measured yet
  double slope_ = 0;  // its filtered change per revolution
};

// Shared by K and L: the integral law in u = f^alpha that gives
// F(k+1) = p F(k) + (1 - p) F_ref for a process F = G u with p = exp(-T/tau):
//   u(k) = u(k-1) + (1 - p) (F_ref - F(k)) / G,
// clamped to the feed limits (the clamp is the anti-windup: the integrator
// state is u itself).
class ForceLaw {
 public:
  void configure(double alpha, double min_fpt, double max_fpt, double time_constant_s,
                 double period_s) noexcept;
  void start(double feed_per_tooth_mm) noexcept;
  // The time since the last step (one revolution at the measured speed);
  // the pole follows it, so the closed loop keeps its time constant.
  void set_period(double period_s) noexcept;
  // One step; returns the new feed per tooth. gain in N / (mm/tooth)^alpha.
  double step(double force_n, double reference_n, double gain, double max_fpt_now) noexcept;
  double feed_per_tooth() const noexcept;
  double pole() const noexcept { return pole_; }

 private:
  double alpha_ = 1, u_ = 0, u_min_ = 0, u_max_ = 0, pole_ = 0;
  double time_constant_s_ = 1, period_s_ = 0;
  double last_reference_n_ = 0;  // 0: none yet (no feedforward on the first step)
};

// K: adaptive force controller: the law above with H's gain estimate.
class AdaptiveForceController final : public Module {
 public:
  AdaptiveForceController() noexcept : Module(ModuleId::K) {}
  Period period() const noexcept override { return Period::kRevolution; }
  bool starts_on_activation() const noexcept override { return true; }
  SignalMask writes() const noexcept override { return mask(Signal::kControllerFeed); }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override { s.controller_valid = false; }
  Status update(Signals& s) noexcept override;

 private:
  EdgeParameters p_;
  ForceLaw law_;
  bool started_ = false;
};

// L: model-based force controller (eq. 1): the law above with G = K d^beta
// from the force-process model, started at the model's feed for F_ref.
class ModelBasedForceController final : public Module {
 public:
  ModelBasedForceController() noexcept : Module(ModuleId::L) {}
  Period period() const noexcept override { return Period::kRevolution; }
  bool starts_on_activation() const noexcept override { return true; }
  SignalMask writes() const noexcept override { return mask(Signal::kControllerFeed); }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override { s.controller_valid = false; }
  Status update(Signals& s) noexcept override;

 private:
  EdgeParameters p_;
  ForceLaw law_;
  bool started_ = false;
};

// F: chatter suppressor. Serves each request of G (rewrite_requests) once:
// rewrites the remaining part program to one more pass of equal depths
// (add_one_pass in program.hpp) and reports it; the core hands the new
// program to the drive. Reaches the program through attach().
class ChatterSuppressor final : public Module {
 public:
  ChatterSuppressor() noexcept : Module(ModuleId::F) {}
  Period period() const noexcept override { return Period::kEvent; }
  SignalMask writes() const noexcept override { return mask(Signal::kProgramRewritten); }
  void configure(const EdgeParameters&) override {}
  void attach(RunningProgram& program) noexcept override { program_ = &program; }
  void reset() noexcept override {}
  // Called with reset(): requests made before it are not served (never replayed).
  void clear_outputs(Signals& s) noexcept override { served_ = s.rewrite_requests; }
  bool requested(const Signals& s) const noexcept override { return s.rewrite_requests != served_; }
  Status update(Signals& s) noexcept override;

 private:
  RunningProgram* program_ = nullptr;
  uint32_t served_ = 0;
};

// One of the paper's modules A–L (the registry's factory; registry.hpp).
std::unique_ptr<Module> make_module(ModuleId id);

// N: tool-breakage detector (beyond Table 1; edge/README.md has the method
// and the study). Splits each revolution of the core's revolution clock into
// one window per tooth and follows the resultant force |F| in each, sample
// by sample from an eighth of the window on, against the same arc one
// revolution earlier (after Tlusty and Tarng's differences across teeth and
// revolutions; read between samples where this window's first sample lies,
// as a revolution need not be a whole number of samples). A window falling
// beyond the windows' common change by more than `breakage_threshold` x the
// mean window force, by twice the other windows' spread (chatter moves
// every window; the window before, if it fell, is left out: a tooth's arc
// may straddle the two), and by more than the threshold as a share of its
// own force beyond the others' median share (with runout a common change
// moves each window in proportion to its force), is a tooth that lost its
// chip. The common change is the smaller of the median of the windows'
// last changes and the last closed window's (entry, exit, depth and feed changes
// move every window; runout repeats and cancels); a window's own fall the
// revolution before is taken off (a trend) but while leaving the part. No
// decision in the first three compared revolutions but a certain one, nor
// below 0.75 x the contact threshold. After the feed fell by more than 5 %
// over a revolution, or once the drive's engagement is below the most it
// reported (the cutter leaving the part), a fall (from a quarter of its
// window on) is only a suspect, one per window: confirmed when another
// window within the cut's arc has taken the chip (risen by half the
// threshold's share of the mean window, beyond the common change and by
// half that in itself) within a revolution before or after the window's
// last fall. Leaving the part, every window is also judged against its
// neighbours in time (the windows before and after it) with the last sample
// of the window after it: a fall beyond their mean change by more than the
// threshold's share of the mean window is a lost chip, a rise beyond it a
// taken one (every window falls through an exit, the taker too). A gap in the
// samples (N was inactive) restarts the windows a revolution after N
// resumes (at once when it resumes as the cutter enters the part: nothing
// sprang back). f is latched until N is reset.
class ToolBreakageDetector final : public Module {
 public:
  ToolBreakageDetector() noexcept : Module(ModuleId::N) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kToolBreakage); }
  bool takes_samples() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override;
  void reset() noexcept override;
  void clear_outputs(Signals& s) noexcept override {
    s.tool_broken = false;
    s.breakage_window = -1;
    s.breakage_drop = 0;
  }
  Status on_sample(Signals& s) noexcept override;
  Status update(Signals&) noexcept override { return Status::kOk; }

  // For the breakage study: the largest score of an immediate decision (the
  // drop beyond the common change, share of the mean window force) since the
  // last call, whether it fired or not (suspects are left out: confirmation
  // decides them; so are falls within twice the spread or not standing out
  // as a share of the window's own force); each window's change over the
  // last revolution and mean.
  double take_largest_score() noexcept {
    const double v = largest_score_;
    largest_score_ = 0;
    return v;
  }
  const double* window_changes() const noexcept { return change_; }
  // The mean window force below which N does not judge.
  static double force_floor_n(const EdgeParameters& p) noexcept {
    return kFloorShare * p.contact_threshold_n;
  }
  const double* window_means() const noexcept { return previous_; }

 private:
  static constexpr int kMaxTeeth = 64;
  void restart() noexcept;
  void close_window() noexcept;
  // Window j's sum one revolution ago over its samples before (fractional)
  // index x, x in [-1, its count + 1].
  double earlier_sum(int j, double x) const noexcept;
  // change: this window's mean so far less the same arc's a revolution
  // before (earlier).
  void judge(Signals& s, double change, double earlier) noexcept;
  // The median of the other compared windows' last changes, each as a share
  // of its own mean the revolution before.
  double relative_common(int exclude) const noexcept;
  void judge_pending(Signals& s) noexcept;
  // Leaving the part: the window before `j` against its neighbours in time,
  // j's change and mean being change_j and mean_j (j whole, or just closed;
  // compared).
  void judge_exit(Signals& s, int j, double change_j, double mean_j) noexcept;
  // The windows' mean force one revolution ago (the scores' scale).
  double mean_window() const noexcept;
  // The drive's engagement is below the most it reported since the
  // (re)start: the cutter is leaving the part (NaN: not known, not leaving).
  bool leaving_part(const Signals& s) const noexcept { return s.engagement < most_engaged_ - 1e-9; }
  // Window a can hold the chip a broken tooth in window b left: another
  // window within reach_ of it, either way round (the next tooth cuts it a
  // window later, and its arc spans reach_ windows; the spindle may turn
  // with or against the teeth's numbering).
  bool adjacent(int a, int b) const noexcept;
  int reach_ = 1;
  // The median of the last changes of the windows compared since the
  // (re)start, leaving `exclude` out (-1: none); `count` gets how many.
  double compared_median(int exclude, int& count) const noexcept;
  EdgeParameters p_;
  int stride_ = 0;                  // samples kept per window (the longest window)
  std::vector<double> cumulative_;  // per window: running sums of |F|, one revolution ago
  std::vector<double> current_;     // this window's running sums
  int previous_count_[kMaxTeeth] = {};
  double previous_offset_[kMaxTeeth] = {};  // its first sample past its start, in samples
  double previous_lead_[kMaxTeeth] = {};    // |F| of the sample just before its first
  double offset_ = 0;                       // the same two for the window being summed
  double lead_ = 0;
  double last_phase_ = 0;                       // the revolution phase at the last sample
  double last_force_ = 0;                       // and |F|
  double previous_[kMaxTeeth] = {};             // window means, one revolution ago
  double change_[kMaxTeeth] = {};               // each window's last change of mean
  double excess_[kMaxTeeth] = {};               // and its fall beyond the common change then
  double excess_before_[kMaxTeeth] = {};        // the same, the revolution before
  double change_before_[kMaxTeeth] = {};        // each window's change the revolution before
  static constexpr double kSpreadFactor = 2.0;  // a break's fall x the others' spread
  static constexpr int kSettleRevolutions = 3;  // compared revolutions before a decision
  static constexpr double kCertainDrop = 0.9;   // ... but for a fall this large (x mean window)
  static constexpr double kFloorShare = 0.75;   // judged above this x the contact threshold
  static constexpr double kFeedFall = 0.05;     // a suspect after the feed fell more than this
  static constexpr double kConfirmShare = 0.5;  // x threshold x mean window: the chip taken
  static constexpr int kJudgeFrom = 8;          // judged from 1/kJudgeFrom of a window on
  static constexpr int kSuspectFrom = 4;        // a suspect from 1/kSuspectFrom of a window on
  static constexpr double kFromAir = 0.25;      // resuming below this engagement: entering
  double feed_before_[kMaxTeeth] = {};          // feed command when each window last closed
  double feed_before2_[kMaxTeeth] = {};         // and the revolution before
  double feed_now_ = 0;
  double most_engaged_ = 0;  // the most engagement the drive reported since the (re)start
  // Suspects: falls after a falling feed or while leaving the part, each
  // awaiting another window's rise (0: none), and closed_ when first seen.
  double suspect_drop_[kMaxTeeth] = {};
  int suspect_closed_[kMaxTeeth] = {};
  int closed_ = 0;  // windows compared since the (re)start
  bool have_previous_[kMaxTeeth] = {};
  bool compared_[kMaxTeeth] = {};  // change_ is from a comparison since the (re)start
  // A certain fall seen before two other windows were compared (the first
  // compared revolution): decided once they are, against their median.
  int pending_window_ = -1;
  double pending_mean_ = 0;
  static constexpr int kMinPeers = 2;  // other windows compared for a common change
  int window_ = -1;                    // the window being summed
  bool partial_ = false;               // sampling started inside it: not compared
  double unfilled_ = 0;                // revolutions to pass after a gap before filling
  int count_ = 0;                      // its samples so far
  double last_t_s_ = -1;               // time of the last sample taken (a gap restarts the windows)
  double largest_score_ = 0;
};

// O: spindle-speed chatter suppressor (beyond Table 1; edge/README.md). When
// activated (SMC II+, in place of the added pass for the first chatter of a
// pass) it reads the chatter frequency f_c that E measured and commands the
// spindle speed whose tooth-passing frequency is (1 - margin) x f_c / k for
// the smallest whole k that keeps the speed within the machine's range and
// [1 / ratio, ratio] x the programmed speed (Tlusty and Smith's rule; the
// margin aims at the middle of the stable pocket). The feed is held until
// the spindle is at speed (g); the core passes the command to the drive and
// the program's remaining passes follow it. No usable speed: g at once
// without a change (the next chatter of the pass adds a pass).
class SpindleSpeedChatterSuppressor final : public Module {
 public:
  SpindleSpeedChatterSuppressor() noexcept : Module(ModuleId::O) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kSpeedChange); }
  bool resets_on_activation() const noexcept override { return true; }
  void configure(const EdgeParameters& p) override { p_ = p; }
  void attach(RunningProgram& program) noexcept override { program_ = &program; }
  void reset() noexcept override {
    started_ = false;
    elapsed_s_ = 0;
  }
  void clear_outputs(Signals& s) noexcept override {
    s.spindle_speed_cmd_rpm = 0;
    s.speed_change_done = false;
  }
  Status update(Signals& s) noexcept override;

  // The speed the rule picks for a chatter frequency at a programmed speed;
  // 0 when none is usable. Real-time safe.
  static double pick_speed(const EdgeParameters& p, double chatter_hz, double programmed_rpm,
                           double current_rpm) noexcept;

 private:
  EdgeParameters p_;
  RunningProgram* program_ = nullptr;
  bool started_ = false;
  double elapsed_s_ = 0;
};

}  // namespace smc::edge
