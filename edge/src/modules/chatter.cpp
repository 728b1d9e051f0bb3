// Module E: automatic chatter detector.

#include <algorithm>
#include <cmath>
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
  const auto n = static_cast<size_t>(p.samples_per_revolution);
  buffer_.assign(n, 0.0);
  spectrum_.assign(n / 2 + 1, {});
  // Run once so that the FFT plan and its scratch buffers exist before the
  // loop starts: later calls of the same size do not allocate.
  fft_->fft.fwd(spectrum_, buffer_);
  reset();
}

void AutomaticChatterDetector::reset() noexcept {
  filled_ = 0;
  above_ = 0;
}

Status AutomaticChatterDetector::on_sample(Signals& s) noexcept {
  if (filled_ < static_cast<int>(buffer_.size())) {
    buffer_[static_cast<size_t>(filled_++)] = s.sample.f_z_n;
  }
  return Status::kOk;
}

double AutomaticChatterDetector::statistic(double spindle_rpm, double* frequency_hz) noexcept {
  const size_t n = buffer_.size();
  double mean = 0;
  for (double v : buffer_) mean += v;
  mean /= static_cast<double>(n);
  double ac_power = 0;
  for (double& v : buffer_) {
    v -= mean;
    ac_power += v * v;
  }
  const double rms = std::sqrt(ac_power / static_cast<double>(n));
  if (frequency_hz != nullptr) *frequency_hz = 0;
  if (rms < p_.chatter_min_rms_n) return 0.0;

  fft_->fft.fwd(spectrum_, buffer_);
  const double fs = 1.0 / p_.sample_period_s;
  const double df = fs / static_cast<double>(n);
  const double tooth_hz = p_.teeth * spindle_rpm / 60.0;
  double total = 0, chatter = 0, peak = 0;
  for (size_t k = 1; k < spectrum_.size(); ++k) {
    const double e = std::norm(spectrum_[k]);
    total += e;
    const double f = static_cast<double>(k) * df;
    if (f < p_.chatter_band_low_hz || f > p_.chatter_band_high_hz) continue;
    const double nearest = tooth_hz > 0 ? std::round(f / tooth_hz) * tooth_hz : 0;
    if (std::fabs(f - nearest) <= p_.harmonic_guard_hz) continue;
    chatter += e;
    if (e > peak) {
      peak = e;
      if (frequency_hz != nullptr) *frequency_hz = f;
    }
  }
  return total > 0 ? chatter / total : 0.0;
}

Status AutomaticChatterDetector::update(Signals& s) noexcept {
  if (filled_ < static_cast<int>(buffer_.size())) {
    // A partial revolution (the detector was just activated): no decision.
    filled_ = 0;
    return Status::kOk;
  }
  double freq = 0;
  const double ratio = statistic(s.spindle_rpm, &freq);
  filled_ = 0;
  if (!std::isfinite(ratio)) return Status::kError;
  s.chatter_ratio = ratio;
  s.chatter_frequency_hz = freq;
  above_ = ratio > p_.chatter_threshold ? above_ + 1 : 0;
  if (above_ >= p_.chatter_confirm_revolutions) s.chatter_detected = true;
  return Status::kOk;
}

}  // namespace smc::edge
