#pragma once
// The anti-alias filter in front of a force sensor's sampler: a Butterworth
// low-pass of even order (2 by default, up to kMaxOrder) as a cascade of
// second-order sections by the bilinear transform (with pre-warping), run at
// the simulator's internal step over the force of every internal step
// (StepForceTrace). The simulated mill and the virtual dynamometer on
// LinuxCNC model their sensor with it, so the two plants read alike.
// Real-time safe: no allocation; a decaying state is flushed to zero so that
// it never sinks into subnormal numbers (which would make each step a hundred
// times slower in air).

#include <array>
#include <cmath>
#include <numbers>

namespace smc::machining {

class AntiAliasLowPass {
 public:
  static constexpr int kMaxOrder = 8;
  // An order a configuration may give: 0 (the second) or even, 2-kMaxOrder.
  static constexpr bool is_order(unsigned order) noexcept {
    return order <= static_cast<unsigned>(kMaxOrder) && order % 2 == 0;
  }

  // A cut-off of 0, or at or above Nyquist, means no filtering worth the
  // name: the filter then sits at 0.45 x the rate. An odd or out-of-range
  // order is the caller's error (the configurations are checked before).
  void configure(double cutoff_hz, double rate_hz, int order = 2) noexcept {
    if (!(cutoff_hz > 0 && cutoff_hz < rate_hz / 2)) cutoff_hz = rate_hz * 0.45;
    if (order < 2 || order > kMaxOrder || order % 2 != 0) order = 2;
    sections_ = order / 2;
    const double k = std::tan(std::numbers::pi * cutoff_hz / rate_hz);
    for (int i = 0; i < sections_; ++i) {
      // The Butterworth poles in conjugate pairs: section i's quality factor
      // is 1 / (2 cos θ_i), θ_i = (2i + 1) π / (2 order).
      const double theta = (2.0 * i + 1) * std::numbers::pi / (2.0 * order);
      const double q = 1 / (2 * std::cos(theta));
      Section& s = sections_at_[static_cast<size_t>(i)];
      const double norm = 1.0 / (1.0 + k / q + k * k);
      s.b0 = k * k * norm;
      s.b1 = 2 * s.b0;
      s.b2 = s.b0;
      s.a1 = 2 * (k * k - 1) * norm;
      s.a2 = (1 - k / q + k * k) * norm;
    }
    reset();
  }
  int order() const noexcept { return 2 * sections_; }
  void reset() noexcept {
    for (Section& s : sections_at_) s.z1 = s.z2 = 0;
  }
  double operator()(double x) noexcept {
    for (int i = 0; i < sections_; ++i) {
      Section& s = sections_at_[static_cast<size_t>(i)];
      const double y = s.b0 * x + s.z1;
      s.z1 = s.b1 * x - s.a1 * y + s.z2;
      s.z2 = s.b2 * x - s.a2 * y;
      if (std::fabs(s.z1) < 1e-30) s.z1 = 0;
      if (std::fabs(s.z2) < 1e-30) s.z2 = 0;
      x = y;
    }
    return x;
  }

 private:
  struct Section {
    double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0, z1 = 0, z2 = 0;
  };
  std::array<Section, kMaxOrder / 2> sections_at_{};
  int sections_ = 1;
};

}  // namespace smc::machining
