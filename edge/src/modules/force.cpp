// Modules H (parameter estimator), I (force signal processor), J (contact
// monitor), K (adaptive force controller), L (model-based force controller).

#include <algorithm>
#include <cmath>

#include "smc/edge/modules.hpp"

namespace smc::edge {

// ---------------------------------------------------------------- I, J --

Status ForceSignalProcessor::on_sample(Signals& s) noexcept {
  peak_ = std::max(peak_, std::fabs(s.sample.f_y_n));
  return Status::kOk;
}

Status ForceSignalProcessor::update(Signals& s) noexcept {
  s.f_y_peak_n = peak_;
  s.f_y_updated = true;
  ++s.revolutions;
  peak_ = 0;
  return Status::kOk;
}

Status ContactMonitor::update(Signals& s) noexcept {
  // Contact is found on any revolution with F_Y above the threshold, lost
  // only on one cut at a feed throughout (after a hold in the part the force
  // builds up again) with F_Y below kRelease x the threshold: a cut whose
  // F_Y lies near the threshold keeps its contact.
  if (s.f_y_peak_n > threshold_) {
    s.contact = true;
  } else if (!held_ && s.f_y_peak_n < kRelease * threshold_) {
    s.contact = false;
  }
  held_ = false;
  return Status::kOk;
}

// ------------------------------------------------------------------- M --

void SpindlePowerMonitor::configure(const EdgeParameters& p) {
  p_ = p;
  reset();
}

void SpindlePowerMonitor::reset() noexcept {
  rho_ = 0;
  slope_ = 0;
  sum_w_ = 0;
  samples_ = 0;
  estimated_ = false;
}

Status SpindlePowerMonitor::on_sample(Signals& s) noexcept {
  double w = s.spindle_power_w;
  if (std::isnan(w)) {
    const double v = supervision::cutting_speed_m_s(p_.cutter_radius_mm, s.spindle_rpm);
    w = v * std::hypot(s.sample.f_x_n, s.sample.f_y_n);
    estimated_ = true;
  }
  if (std::isfinite(w)) {
    sum_w_ += w;
    ++samples_;
  }
  return Status::kOk;
}

Status SpindlePowerMonitor::update(Signals& s) noexcept {
  if (samples_ == 0) {
    s.force_reference_scale = s.force_reference_planned ? 1.0 : p_.power_target_fraction;
    return Status::kOk;
  }
  const double mean = sum_w_ / samples_;
  s.power_mean_w = mean;
  s.power_estimated = estimated_;
  sum_w_ = 0;
  samples_ = 0;
  estimated_ = false;
  const ModuleMask held = static_cast<ModuleMask>(bit(ModuleId::C) | bit(ModuleId::G));
  const double limit = p_.power_target_fraction * p_.max_spindle_power_w / p_.force_safety_factor;
  const double v = supervision::cutting_speed_m_s(p_.cutter_radius_mm, s.spindle_rpm);
  // Learn the ratio only from a revolution cut under normal conditions: in
  // contact, feeding, no hold, with a real power and force to compare.
  if (s.contact && s.in_pass && (s.active & held) == 0 && mean > 0.05 * limit && v > 0 &&
      s.f_y_peak_n > p_.contact_threshold_n) {
    const double rho = mean / (v * s.f_y_peak_n);
    const double revolution_s = 60.0 / s.spindle_rpm;
    const double g = 1.0 - std::exp(-revolution_s / p_.power_time_constant_s);
    if (rho_ > 0) {
      // The ratio only rises within a job: the cutter leaving the part
      // lowers it, and the next entry should start from what the full cut
      // showed rather than from P_max / V.
      const double before = rho_;
      if (rho > rho_) rho_ += g * (rho - rho_);
      slope_ += g * ((rho_ - before) - slope_);
    } else {
      rho_ = rho;
      slope_ = 0;
    }
  }
  // While the ratio rises (the cutter entering the part), lead it by the
  // revolutions the force takes to follow a new F_ref: measured on one
  // revolution, applied from the next, reached by the end of that one.
  const double rho_ahead = rho_ + kLeadRevolutions * std::max(0.0, slope_);
  // F_ref never exceeds the base; P_max / V (not a planned F_ref) takes the
  // same share of the limit as the power, so the first revolutions of a cut,
  // before the ratio is known, keep the margin too.
  const double cap = s.force_reference_planned ? 1.0 : p_.power_target_fraction;
  s.force_reference_scale = cap;
  if (rho_ahead > 0 && v > 0 && s.force_reference_base_n > 0) {
    // Above the target the revolution's own excess is taken off as well
    // (the force controller lagging a rising engagement).
    const double f_ref = limit / (v * rho_ahead) * std::min(1.0, limit / mean);
    s.force_reference_scale = std::clamp(f_ref / s.force_reference_base_n, kMinScale, cap);
  }
  return std::isfinite(s.force_reference_scale)
             ? Status::kOk
             : fail("the spindle power's force reference is not finite");
}

// ------------------------------------------------------------------- H --

void ParameterEstimator::configure(const EdgeParameters& p) {
  p_ = p;
  reset();
}

void ParameterEstimator::reset() noexcept {
  theta_ = 0;
  covariance_ = 0;
  initialised_ = false;
}

Status ParameterEstimator::update(Signals& s) noexcept {
  // The F_Y just measured was produced by the feed the routine (A) has been
  // commanding during that revolution: the controllers change their output
  // only at revolution boundaries, and A runs after them.
  const double f = s.feed_per_tooth_cmd_mm;
  if (!s.f_y_updated || !s.contact || f <= 0) return Status::kOk;
  const double phi = std::pow(f, p_.adaptive_feed_exponent);
  const double y = s.f_y_peak_n;
  if (!std::isfinite(phi) || !std::isfinite(y) || phi <= 0) {
    return fail("the gain estimate's regressor or the revolution's F_y is not finite");
  }
  if (!initialised_) {
    // First measurement: the one-sample estimate, with a covariance that lets
    // the next few revolutions move it freely.
    theta_ = y / phi;
    covariance_ = 10.0 / (phi * phi);
    initialised_ = true;
  } else {
    const double lambda = p_.rls_forgetting;
    const double denom = lambda + phi * covariance_ * phi;
    const double gain = covariance_ * phi / denom;
    theta_ += gain * (y - phi * theta_);
    covariance_ = (covariance_ - gain * phi * covariance_) / lambda;
    // Bound the covariance so forgetting cannot blow it up without excitation.
    covariance_ = std::min(covariance_, 100.0 / (phi * phi));
  }
  if (!(theta_ > 0) || !std::isfinite(theta_)) {
    return fail("the estimated process gain is not positive and finite");
  }
  s.gain_estimate = theta_;
  s.gain_valid = true;
  return Status::kOk;
}

// ------------------------------------------------------------- K, L law --

void ForceLaw::configure(double alpha, double min_fpt, double max_fpt, double time_constant_s,
                         double period_s) noexcept {
  alpha_ = alpha;
  u_min_ = std::pow(min_fpt, alpha);
  u_max_ = std::pow(max_fpt, alpha);
  time_constant_s_ = time_constant_s;
  period_s_ = 0;
  set_period(period_s);
  u_ = u_min_;
}

void ForceLaw::set_period(double period_s) noexcept {
  if (period_s == period_s_ || !(period_s > 0)) return;
  period_s_ = period_s;
  pole_ = std::exp(-period_s / time_constant_s_);
}

void ForceLaw::start(double feed_per_tooth_mm) noexcept {
  u_ = std::clamp(std::pow(std::max(feed_per_tooth_mm, 0.0), alpha_), u_min_, u_max_);
  last_reference_n_ = 0;
}

double ForceLaw::step(double force_n, double reference_n, double gain,
                      double max_fpt_now) noexcept {
  const double u_max = std::min(u_max_, std::pow(max_fpt_now, alpha_));
  // Feedback with the pole p, and the reference's own change fed forward:
  // a constant F_ref gives the law above; a step of F_ref (M lowering it)
  // moves the force in one period instead of over tau.
  const double change = last_reference_n_ > 0 ? reference_n - last_reference_n_ : 0.0;
  last_reference_n_ = reference_n;
  u_ += ((1.0 - pole_) * (reference_n - force_n) + change) / gain;
  u_ = std::clamp(u_, u_min_, std::max(u_min_, u_max));
  return feed_per_tooth();
}

double ForceLaw::feed_per_tooth() const noexcept { return std::pow(u_, 1.0 / alpha_); }

namespace {

// The most feed per tooth the machine allows at this spindle speed.
double max_feed_now(const EdgeParameters& p, double rpm) noexcept {
  return std::min(p.max_feed_per_tooth_mm, p.feed_per_tooth_for(p.max_feedrate_mm_s, rpm));
}

}  // namespace

// ------------------------------------------------------------------- K --

void AdaptiveForceController::configure(const EdgeParameters& p) {
  p_ = p;
  law_.configure(p.adaptive_feed_exponent, p.min_feed_per_tooth_mm, p.max_feed_per_tooth_mm,
                 p.adaptive_time_constant_s, p.slow_period_s);
  reset();
}

void AdaptiveForceController::reset() noexcept { started_ = false; }

Status AdaptiveForceController::update(Signals& s) noexcept {
  if (!started_) {
    // Bumpless start from the programmed feed: no model to do better --
    // except after a spindle speed change within the pass (module O), where
    // the depth is the same and H's gain still holds: then the feed that
    // gain gives for the new F_ref (P_max / V falls as the speed rises), if
    // lower. Starting from the programmed feed there overshoots the power.
    double start = p_.feed_per_tooth_for(s.programmed_feedrate_mm_s, s.spindle_rpm);
    if (s.speed_changed_in_pass && s.gain_valid && s.gain_estimate > 0 && s.force_reference_n > 0) {
      const double warm =
          std::pow(s.force_reference_n / s.gain_estimate, 1.0 / p_.adaptive_feed_exponent);
      if (std::isfinite(warm) && warm > 0) start = std::min(start, warm);
    }
    law_.start(start);
    started_ = true;
  } else if (s.f_y_updated && s.gain_valid) {
    law_.set_period(s.revolution_period_s);
    law_.step(s.f_y_peak_n, s.force_reference_n, s.gain_estimate, max_feed_now(p_, s.spindle_rpm));
  }
  s.controller_feed_per_tooth_mm = law_.feed_per_tooth();
  s.controller_valid = true;
  return std::isfinite(s.controller_feed_per_tooth_mm)
             ? Status::kOk
             : fail("the force controller's feed is not finite");
}

// ------------------------------------------------------------------- L --

void ModelBasedForceController::configure(const EdgeParameters& p) {
  if (!p.has_force_model) {
    throw ConfigError(
        "supervisor_config.force_model: module L needs a force-process model (k_kn, beta, "
        "alpha > 0); give one, or run SMC II without L");
  }
  p_ = p;
  law_.configure(p.model_alpha, p.min_feed_per_tooth_mm, p.max_feed_per_tooth_mm,
                 p.model_time_constant_s, p.slow_period_s);
  reset();
}

void ModelBasedForceController::reset() noexcept { started_ = false; }

Status ModelBasedForceController::update(Signals& s) noexcept {
  // G = K d^beta, in N per (mm/tooth)^alpha.
  const double gain = 1000.0 * p_.model_k_kn * std::pow(s.depth_mm, p_.model_beta);
  if (!(gain > 0) || !std::isfinite(gain)) {
    return fail("the force model's gain at this depth is not positive and finite");
  }
  if (!started_) {
    // Start at the model's feed for the reference, never above the program.
    const double model_feed = std::pow(s.force_reference_n / gain, 1.0 / p_.model_alpha);
    const double programmed = p_.feed_per_tooth_for(s.programmed_feedrate_mm_s, s.spindle_rpm);
    law_.start(std::min(model_feed, programmed));
    started_ = true;
  } else if (s.f_y_updated) {
    law_.set_period(s.revolution_period_s);
    law_.step(s.f_y_peak_n, s.force_reference_n, gain, max_feed_now(p_, s.spindle_rpm));
  }
  s.controller_feed_per_tooth_mm = law_.feed_per_tooth();
  s.controller_valid = true;
  return std::isfinite(s.controller_feed_per_tooth_mm)
             ? Status::kOk
             : fail("the force controller's feed is not finite");
}

}  // namespace smc::edge
