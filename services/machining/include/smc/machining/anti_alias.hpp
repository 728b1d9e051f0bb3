#pragma once
// The anti-alias filter in front of a force sensor's sampler: a second-order
// Butterworth low-pass by the bilinear transform (with pre-warping), run at
// the simulator's internal step over the force of every internal step
// (StepForceTrace). The simulated mill and the virtual dynamometer on
// LinuxCNC model their sensor with it, so the two plants read alike.
// Real-time safe: no allocation; a decaying state is flushed to zero so that
// it never sinks into subnormal numbers (which would make each step a hundred
// times slower in air).

#include <cmath>
#include <numbers>

namespace smc::machining {

class AntiAliasLowPass {
 public:
  // A cut-off of 0, or at or above Nyquist, means no filtering worth the
  // name: the filter then sits at 0.45 x the rate.
  void configure(double cutoff_hz, double rate_hz) noexcept {
    if (!(cutoff_hz > 0 && cutoff_hz < rate_hz / 2)) cutoff_hz = rate_hz * 0.45;
    const double k = std::tan(std::numbers::pi * cutoff_hz / rate_hz);
    const double q = std::numbers::sqrt2 / 2;
    const double norm = 1.0 / (1.0 + k / q + k * k);
    b0_ = k * k * norm;
    b1_ = 2 * b0_;
    b2_ = b0_;
    a1_ = 2 * (k * k - 1) * norm;
    a2_ = (1 - k / q + k * k) * norm;
    reset();
  }
  void reset() noexcept { z1_ = z2_ = 0; }
  double operator()(double x) noexcept {
    const double y = b0_ * x + z1_;
    z1_ = b1_ * x - a1_ * y + z2_;
    z2_ = b2_ * x - a2_ * y;
    if (std::fabs(z1_) < 1e-30) z1_ = 0;
    if (std::fabs(z2_) < 1e-30) z2_ = 0;
    return y;
  }

 private:
  double b0_ = 1, b1_ = 0, b2_ = 0, a1_ = 0, a2_ = 0, z1_ = 0, z2_ = 0;
};

}  // namespace smc::machining
