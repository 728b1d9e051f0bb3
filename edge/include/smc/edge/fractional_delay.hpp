// A sampled signal's value between its samples: a band-limited fractional
// delay (a Kaiser-windowed sinc), for comparing a revolution with the one
// before at the same spindle angle when a revolution is not a whole number
// of samples.
//
// Linear interpolation is not good enough there. It is a low-pass filter
// whose loss depends on where between the samples the point falls: halfway
// between them, a 650 Hz component (the tool mode) sampled at 2 kHz comes
// out at 0.52 of its amplitude, so a vibration that repeats exactly reads as
// a change of 48 % of that component (edge/CHATTER.md). With 16
// taps each side and a Kaiser window of beta 5, scaled so that a constant
// passes exactly, a tone's error is below 0.2 % up to 0.65 of the Nyquist
// frequency, 0.3 % up to 0.8 and 0.5 % up to 0.9, wherever the point falls
// between the samples (tests/unit/edge/fractional_delay_test.cpp).
//
// Nothing here allocates: the taps live in a fixed array, so module E uses
// it in the real-time loop.
#pragma once

#include <array>
#include <cmath>
#include <complex>

namespace smc::edge {

class FractionalDelay {
 public:
  static constexpr int kMaxHalf = 16;  // taps each side of the point
  static constexpr double kBeta = 5;   // the Kaiser window's

  // The taps for a point `u` samples (in [0, 1)) past sample j0, with
  // `half` taps each side (1 to kMaxHalf): samples j0 - half + 1 ... j0 +
  // half. At u = 0 it is sample j0 itself.
  // The same point and taps again cost nothing (the speed holds for many
  // revolutions).
  void set(double u, int half) noexcept {
    half = half < 1 ? 1 : (half > kMaxHalf ? kMaxHalf : half);
    if (ready_ && u == u_ && half == half_) return;
    ready_ = true;
    half_ = half;
    u_ = u;
    if (!(u > 0)) {
      taps_.fill(0);
      taps_[static_cast<size_t>(half_ - 1)] = 1;
      return;
    }
    const double norm = bessel_i0(kBeta);
    double sum = 0;
    for (int i = 0; i < 2 * half_; ++i) {
      const double x = u - static_cast<double>(i - half_ + 1);  // distance from the tap
      const double r = x / half_;
      const double window = bessel_i0(kBeta * std::sqrt(std::fmax(0.0, 1 - r * r))) / norm;
      const double px = 3.14159265358979323846 * x;
      taps_[static_cast<size_t>(i)] = std::sin(px) / px * window;
      sum += taps_[static_cast<size_t>(i)];
    }
    // A constant passes unchanged.
    for (int i = 0; i < 2 * half_; ++i) taps_[static_cast<size_t>(i)] /= sum;
  }

  int half() const noexcept { return half_; }
  double fraction() const noexcept { return u_; }

  // The value at the point: `value(j)` is sample j.
  template <class Value, class Index>
  double at(const Value& value, Index j0) const noexcept {
    if (!(u_ > 0)) return value(j0);
    double v = 0;
    for (int i = 0; i < 2 * half_; ++i) {
      v += taps_[static_cast<size_t>(i)] *
           value(j0 + static_cast<Index>(i) - static_cast<Index>(half_ - 1));
    }
    return v;
  }

  // |response|^2 at omega * T radians per sample: how much of a white
  // noise's power at that frequency reaches the delayed value.
  double gain_squared(double omega_t) const noexcept {
    if (!(u_ > 0)) return 1;
    const std::complex<double> z = std::polar(1.0, -omega_t);
    std::complex<double> h = 0;
    for (int i = 2 * half_ - 1; i >= 0; --i) h = h * z + taps_[static_cast<size_t>(i)];
    return std::norm(h);
  }

 private:
  static double bessel_i0(double x) noexcept {
    // sum over k of ((x/2)^k / k!)^2, to double precision for x <= 10.
    const double y = 0.25 * x * x;
    double term = 1, sum = 1;
    for (int k = 1; k < 40 && term > 1e-17 * sum; ++k) {
      term *= y / (static_cast<double>(k) * static_cast<double>(k));
      sum += term;
    }
    return sum;
  }

  std::array<double, 2 * kMaxHalf> taps_{};
  int half_ = 1;
  double u_ = 0;
  bool ready_ = false;
};

}  // namespace smc::edge
