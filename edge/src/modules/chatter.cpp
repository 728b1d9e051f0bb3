// Module E: automatic chatter detector.

#include <algorithm>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/FFT>

#include "smc/edge/modules.hpp"

namespace smc::edge {

struct AutomaticChatterDetector::Fft {
  Eigen::FFT<double> fft;
};

AutomaticChatterDetector::AutomaticChatterDetector()
    : Module(ModuleId::E), fft_(std::make_unique<Fft>()) {
  fft_->fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
}

AutomaticChatterDetector::~AutomaticChatterDetector() = default;

void AutomaticChatterDetector::configure(const EdgeParameters& p) {
  p_ = p;
  const auto most = static_cast<size_t>(std::max(p.max_samples_per_revolution, 1));
  buffer_.assign(most, 0.0);
  spectrum_.assign(most / 2 + 1, {});
  // A revolution has as many samples as the measured speed gives it, within
  // the machine's speed range. Plan every FFT size of that range now, the
  // largest last, so that the plans and the scratch buffers exist before the
  // loop starts: later calls of these sizes do not allocate.
  const int fewest = std::clamp(p.min_samples_per_revolution, 1, static_cast<int>(most));
  for (int n = fewest; n <= static_cast<int>(most); ++n) {
    fft_->fft.fwd(spectrum_.data(), buffer_.data(), n);
  }
  reset();
}

void AutomaticChatterDetector::reset() noexcept {
  filled_ = 0;
  above_ = 0;
  previous_mean_ = 0;
  last_engagement_ = std::numeric_limits<double>::quiet_NaN();
  most_engaged_ = last_engagement_;
}

Status AutomaticChatterDetector::on_sample(Signals& s) noexcept {
  if (filled_ < static_cast<int>(buffer_.size())) {
    buffer_[static_cast<size_t>(filled_++)] = s.sample.f_z_n;
  }
  return Status::kOk;
}

double AutomaticChatterDetector::statistic(int samples, double spindle_rpm,
                                           double* frequency_hz) noexcept {
  if (frequency_hz != nullptr) *frequency_hz = 0;
  const int fewest = std::max(p_.min_samples_per_revolution, 4);
  if (samples < fewest || samples > static_cast<int>(buffer_.size())) return 0.0;
  const auto n = static_cast<size_t>(samples);
  double mean = 0;
  for (size_t i = 0; i < n; ++i) mean += buffer_[i];
  mean /= static_cast<double>(n);
  last_mean_ = mean;
  double ac_power = 0;
  for (size_t i = 0; i < n; ++i) {
    buffer_[i] -= mean;
    ac_power += buffer_[i] * buffer_[i];
  }
  const double rms = std::sqrt(ac_power / static_cast<double>(n));
  if (rms < p_.chatter_min_rms_n) return 0.0;

  // One revolution's samples: when the speed is not a whole number of
  // samples per revolution the window is the nearest whole count, and the
  // bins lie within half a sample period's share of the spindle harmonics.
  fft_->fft.fwd(spectrum_.data(), buffer_.data(), static_cast<Eigen::Index>(n));
  const double fs = 1.0 / p_.sample_period_s;
  const double df = fs / static_cast<double>(n);
  const double tooth_hz = p_.teeth * spindle_rpm / 60.0;
  // The bin nearest each tooth harmonic, at most: at low speeds the bins
  // are closer than the configured guard.
  const double guard = std::min(p_.harmonic_guard_hz, 0.6 * df);
  double total = 0, chatter = 0, peak = 0;
  for (size_t k = 1; k <= n / 2; ++k) {
    const double e = std::norm(spectrum_[k]);
    total += e;
    const double f = static_cast<double>(k) * df;
    if (f < p_.chatter_band_low_hz || f > p_.chatter_band_high_hz) continue;
    const double nearest = tooth_hz > 0 ? std::round(f / tooth_hz) * tooth_hz : 0;
    if (std::fabs(f - nearest) <= guard) continue;
    chatter += e;
    if (e > peak) {
      peak = e;
      if (frequency_hz != nullptr) *frequency_hz = f;
    }
  }
  return total > 0 ? chatter / total : 0.0;
}

Status AutomaticChatterDetector::update(Signals& s) noexcept {
  const int samples = filled_;
  filled_ = 0;
  // A partial revolution (the detector was just activated): no decision.
  if (samples != s.revolution_samples) return Status::kOk;
  double freq = 0;
  const double ratio = statistic(samples, s.spindle_rpm, &freq);
  if (!std::isfinite(ratio)) return Status::kError;
  // Entering or leaving the part, or while a controller moves the feed
  // fast, the mean force changes from one revolution to the next and the
  // revolution is not a repetition of the one before: no decision then.
  const double change = std::fabs(last_mean_ - previous_mean_);
  const bool steady = previous_mean_ != 0 && change <= kMaxMeanChange * std::fabs(previous_mean_);
  previous_mean_ = last_mean_;
  // Nor while the cutter leaves the part (the drive's engagement below the
  // most it reached since it last rose: it moves in steps, and may hold for
  // a revolution; NaN: unknown, judged): the part's end takes part of the
  // arc every revolution, however slowly the mean moves, and with runout
  // that change read as chatter at stable exits of the detector study
  // (edge/README.md, module E). Entering, it is judged: most chatter starts
  // there, none started while leaving in that study.
  const double engagement = s.engagement;
  if (!(engagement <= last_engagement_)) most_engaged_ = engagement;  // rose, or was unknown
  last_engagement_ = engagement;
  const bool leaving = engagement < most_engaged_ - 1e-9;
  if (!steady || leaving) {
    s.chatter_ratio = 0;  // not judged
    return Status::kOk;
  }
  s.chatter_ratio = ratio;
  s.chatter_frequency_hz = freq;
  above_ = ratio > p_.chatter_threshold ? above_ + 1 : 0;
  if (above_ >= p_.chatter_confirm_revolutions) s.chatter_detected = true;
  return Status::kOk;
}

}  // namespace smc::edge
