// The band-limited fractional delay that modules E and the chatter label
// read the revolution before with (smc/edge/fractional_delay.hpp).

#include "smc/edge/fractional_delay.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

using smc::edge::FractionalDelay;

namespace {

// The worst error, relative to the amplitude, of a unit tone of each
// frequency up to `most` (a fraction of the Nyquist frequency) read at
// points 0 to 1 sample past a sample, with all the taps.
double worst_error(double most, bool linear) {
  double worst = 0;
  FractionalDelay d;
  for (int iu = 0; iu <= 40; ++iu) {
    const double u = iu / 40.0;
    d.set(u < 1 ? u : 0, FractionalDelay::kMaxHalf);
    const long j0 = u < 1 ? 100 : 101;
    for (int f = 1; f <= 60; ++f) {
      const double omega = std::numbers::pi * most * f / 60.0;  // radians per sample
      auto tone = [&](long j) { return std::polar(1.0, omega * static_cast<double>(j)); };
      const std::complex<double> want = std::polar(1.0, omega * (100 + u));
      std::complex<double> got;
      if (linear) {
        got = (1 - u) * tone(100) + u * tone(101);
      } else {
        got = {d.at([&](long j) { return tone(j).real(); }, j0),
               d.at([&](long j) { return tone(j).imag(); }, j0)};
      }
      worst = std::max(worst, std::abs(got - want));
    }
  }
  return worst;
}

}  // namespace

TEST(FractionalDelay, ReadsATonesValueBetweenSamplesWithinItsStatedError) {
  // The header's figures: below 0.2 % up to 0.65 of Nyquist (the tool mode,
  // 650 Hz at 2 kHz), 0.3 % up to 0.8, 0.5 % up to 0.9.
  EXPECT_LT(worst_error(0.65, false), 0.002);
  EXPECT_LT(worst_error(0.8, false), 0.003);
  EXPECT_LT(worst_error(0.9, false), 0.005);
  // Linear interpolation, for comparison: half a sample past, a tone at
  // 0.65 of Nyquist comes out at 0.52 of its amplitude.
  EXPECT_GT(worst_error(0.65, true), 0.47);
}

TEST(FractionalDelay, ASampleAndAConstantPassUnchanged) {
  FractionalDelay d;
  auto ramp = [](int j) { return 0.5 + 3.0 * j; };
  d.set(0, FractionalDelay::kMaxHalf);
  EXPECT_EQ(d.at(ramp, 40), ramp(40));
  d.set(0.37, 5);
  EXPECT_EQ(d.half(), 5);
  EXPECT_NEAR(d.at([](int) { return 2.5; }, 40), 2.5, 1e-12);
  // Fewer taps than asked for are never more than the most, nor fewer
  // than one.
  d.set(0.5, 100);
  EXPECT_EQ(d.half(), FractionalDelay::kMaxHalf);
  d.set(0.5, 0);
  EXPECT_EQ(d.half(), 1);
}

TEST(FractionalDelay, PassesWhiteNoisesPowerUpToNearTheNyquistFrequency) {
  // The noise E takes out of the change goes through the delay: its power
  // gain is about 1 where the delay is exact, and the same at any point.
  FractionalDelay d;
  for (double u : {0.0, 0.25, 0.5, 0.9}) {
    d.set(u, FractionalDelay::kMaxHalf);
    for (double f : {0.0, 0.3, 0.65, 0.9}) {
      EXPECT_NEAR(d.gain_squared(std::numbers::pi * f), 1.0, 0.01) << u << " " << f;
    }
  }
}
