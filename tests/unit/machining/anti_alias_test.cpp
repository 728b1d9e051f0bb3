// The force sensor's anti-alias filter (anti_alias.hpp): a Butterworth of
// even order whose gain is the one module E's estimate undoes,
// 1 / sqrt(1 + (f / f_c)^(2 order)), the bilinear transform's pre-warping
// aside.

#include "smc/machining/anti_alias.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mc = smc::machining;

namespace {

// Steady-state amplitude of the filter's response to a unit sine at f.
double gain(int order, double cutoff_hz, double rate_hz, double f) {
  mc::AntiAliasLowPass lp;
  lp.configure(cutoff_hz, rate_hz, order);
  const auto steps = static_cast<int>(rate_hz);  // one second
  double peak = 0;
  for (int k = 0; k < steps; ++k) {
    const double y = lp(std::sin(2 * std::numbers::pi * f * k / rate_hz));
    if (k > steps / 2) peak = std::max(peak, std::fabs(y));
  }
  return peak;
}

}  // namespace

// At the simulator's internal rate (80 kHz) the digital filter's gain is the
// analogue Butterworth's that E divides by, within 2 % of it (or 1e-4 of the
// input where it is that small) from 100 Hz to 2 kHz, for every order. (The
// bilinear transform's warping, exact at the cut-off, makes the eighth order
// 1.5 % low at 2 kHz, 0.2 % at 1 kHz: E's band ends there.)
TEST(AntiAliasLowPass, EachOrderHasTheButterworthGainTheEstimateUndoes) {
  const double rate = 80000, fc = 700;
  for (const int order : {2, 4, 6, 8}) {
    for (const double f : {100.0, 400.0, 700.0, 900.0, 1100.0, 1500.0, 2000.0}) {
      const double r = f / fc;
      const double expected = 1 / std::sqrt(1 + std::pow(r * r, order));
      EXPECT_NEAR(gain(order, fc, rate, f), expected, std::max(0.02 * expected, 1e-4))
          << "order " << order << " at " << f << " Hz";
    }
  }
  // At the cut-off every order passes 1/sqrt(2); an octave above, the eighth
  // order passes 1/256 of what the second order's 1/4 is.
  EXPECT_NEAR(gain(8, fc, rate, 2 * fc), 1 / std::sqrt(1 + std::pow(2.0, 16)), 1e-4);
}

// An order the filter does not have falls back to the second order (the
// configurations are checked before: simulation.f_y_wide_order,
// operation.wideband_filter_order).
TEST(AntiAliasLowPass, AnOrderItDoesNotHaveIsTheSecond) {
  for (const int bad : {0, 3, 10, -2}) {
    mc::AntiAliasLowPass lp;
    lp.configure(700, 80000, bad);
    EXPECT_EQ(lp.order(), 2) << bad;
    EXPECT_NEAR(gain(bad, 700, 80000, 1400), gain(2, 700, 80000, 1400), 1e-12) << bad;
  }
}
