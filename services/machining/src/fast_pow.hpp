#pragma once
// x^e1 and x^e2 for the same x, to within a few units in the last place, for
// the power-law forces in the simulator's inner loop (internal). Two libm
// exponentials and a logarithm per tooth and step were half of the
// simulator's time; this shares one decomposition of x between both powers:
//
//   x = 2^k m0 (1 + r),  m0 = 1 + j/256 (j: the top 8 mantissa bits),
//   0 <= r < 1/256,
//   x^e = (2^e)^k * m0^e * (1 + r)^e,
//
// with the first two factors from tables built at construction (one 32-byte
// entry per j, 8 KB in all, so that the lookups stay in the L1 cache) and
// the last from its binomial series to r^7 (error below r^8 < 6e-20),
// evaluated by Estrin's scheme: the simulator is latency-bound, one step
// waits for the previous one's forces. Arguments
// outside the tabulated exponent range, zero, subnormal or non-finite fall
// back to std::pow. Deterministic, allocation-free after construction.

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace smc::machining::detail {

class PowPair {
 public:
  static constexpr int kMinExp = -80;  // 2^-80 mm: far below any chip
  static constexpr int kMaxExp = 40;
  static constexpr int kTable = 256;
  static constexpr int kTerms = 8;  // series coefficients, r^0 .. r^7

  PowPair(double e1, double e2) : e1_(e1), e2_(e2) {
    for (int j = 0; j < kTable; ++j) {
      const double m0 = 1.0 + j / static_cast<double>(kTable);
      table_[static_cast<std::size_t>(j)] = Entry{m0, 1.0 / m0, std::pow(m0, e1), std::pow(m0, e2)};
    }
    const auto n = static_cast<std::size_t>(kMaxExp - kMinExp + 1);
    p2_e1_.resize(n);
    p2_e2_.resize(n);
    for (int k = kMinExp; k <= kMaxExp; ++k) {
      p2_e1_[static_cast<std::size_t>(k - kMinExp)] = std::exp2(k * e1);
      p2_e2_[static_cast<std::size_t>(k - kMinExp)] = std::exp2(k * e2);
    }
    // (1 + r)^e = sum C(e, n) r^n
    double c1 = 1, c2 = 1;
    for (int i = 0; i < kTerms; ++i) {
      c1_[static_cast<std::size_t>(i)] = c1;
      c2_[static_cast<std::size_t>(i)] = c2;
      c1 *= (e1 - i) / (i + 1);
      c2 *= (e2 - i) / (i + 1);
    }
  }

  void operator()(double x, double& y1, double& y2) const noexcept {
    const auto bits = std::bit_cast<std::uint64_t>(x);
    const int k = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
    if (k < kMinExp || k > kMaxExp || (bits >> 63) != 0) {
      y1 = std::pow(x, e1_);
      y2 = std::pow(x, e2_);
      return;
    }
    const Entry& t = table_[static_cast<std::size_t>((bits >> 44) & 0xff)];
    const double m = std::bit_cast<double>((bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull);
    const double r = (m - t.m0) * t.inv_m0;
    const double r2 = r * r;
    const double r4 = r2 * r2;
    const double s1 = ((c1_[0] + c1_[1] * r) + r2 * (c1_[2] + c1_[3] * r)) +
                      r4 * ((c1_[4] + c1_[5] * r) + r2 * (c1_[6] + c1_[7] * r));
    const double s2 = ((c2_[0] + c2_[1] * r) + r2 * (c2_[2] + c2_[3] * r)) +
                      r4 * ((c2_[4] + c2_[5] * r) + r2 * (c2_[6] + c2_[7] * r));
    const auto kk = static_cast<std::size_t>(k - kMinExp);
    const double b1 = p2_e1_[kk] * t.m0_e1;
    const double b2 = p2_e2_[kk] * t.m0_e2;
    y1 = b1 * s1;
    y2 = b2 * s2;
  }

 private:
  struct Entry {
    double m0, inv_m0, m0_e1, m0_e2;
  };
  double e1_, e2_;
  std::array<Entry, kTable> table_{};
  std::array<double, kTerms> c1_{}, c2_{};
  std::vector<double> p2_e1_, p2_e2_;
};

}  // namespace smc::machining::detail
