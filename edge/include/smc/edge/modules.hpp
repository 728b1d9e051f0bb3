#pragma once
// The supervisory modules of the paper's Table 1. Each is a plain object stepped
// by the edge core; see module.hpp for the real-time contract.

#include <complex>
#include <memory>
#include <vector>

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
// harmonic; the statistic is its share of the total AC energy. d is set when
// the statistic exceeds the threshold for `chatter_confirm_revolutions`
// consecutive revolutions and stays set until reset.
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
  }
  Status on_sample(Signals& s) noexcept override;
  Status update(Signals& s) noexcept override;

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
  static constexpr double kMaxMeanChange = 0.1;
};

// G: chatter suppression routine: run F (the core rewrites the program),
// then hold the feed for `suppression_hold_s`; then e.
class ChatterSuppressionRoutine final : public Module {
 public:
  ChatterSuppressionRoutine() noexcept : Module(ModuleId::G) {}
  Period period() const noexcept override { return Period::kFast; }
  SignalMask writes() const noexcept override { return mask(Signal::kSuppression); }
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

// J: contact when F_Y exceeds the threshold (50 N).
class ContactMonitor final : public Module {
 public:
  ContactMonitor() noexcept : Module(ModuleId::J) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return mask(Signal::kContact); }
  void configure(const EdgeParameters& p) override { threshold_ = p.contact_threshold_n; }
  void reset() noexcept override {}
  Status update(Signals& s) noexcept override;

 private:
  double threshold_ = 0;
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

}  // namespace smc::edge
