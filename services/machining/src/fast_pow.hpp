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
// with the first two factors from tables built at construction (8 KB and
// 2 KB, so that the lookups stay in the L1 cache) and the last from its
// binomial series to r^7 (error below r^8 < 6e-20), evaluated by Estrin's
// scheme (short dependency chains: one simulator step waits for the previous
// one's forces). Both powers are computed side by side in the two halves of
// an SSE register, so the second costs almost nothing. Arguments outside the
// tabulated exponent range, zero, subnormal, negative or non-finite fall back
// to std::pow. Deterministic, allocation-free after construction.

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace smc::machining::detail {

class PowPair {
 public:
  // Two doubles in one SSE register (GCC/Clang vector extension).
  using Pair = double __attribute__((vector_size(16)));

  static constexpr int kMinExp = -80;  // 2^-80 mm: far below any chip
  static constexpr int kMaxExp = 40;
  static constexpr int kTable = 256;
  static constexpr int kTerms = 8;  // series coefficients, r^0 .. r^7

  PowPair(double e1, double e2) : e1_(e1), e2_(e2) {
    for (int j = 0; j < kTable; ++j) {
      const double m0 = 1.0 + j / static_cast<double>(kTable);
      table_[static_cast<std::size_t>(j)] =
          Entry{{m0, 1.0 / m0}, {std::pow(m0, e1), std::pow(m0, e2)}};
    }
    p2_.resize(static_cast<std::size_t>(kMaxExp - kMinExp + 1));
    for (int k = kMinExp; k <= kMaxExp; ++k) {
      p2_[static_cast<std::size_t>(k - kMinExp)] = Pair{std::exp2(k * e1), std::exp2(k * e2)};
    }
    // (1 + r)^e = sum C(e, n) r^n
    double c1 = 1, c2 = 1;
    for (int i = 0; i < kTerms; ++i) {
      c_[static_cast<std::size_t>(i)] = Pair{c1, c2};
      c1 *= (e1 - i) / (i + 1);
      c2 *= (e2 - i) / (i + 1);
    }
  }

  void operator()(double x, double& y1, double& y2) const noexcept {
    const Pair y = (*this)(x, Pair{1.0, 1.0});
    y1 = y[0];
    y2 = y[1];
  }

  // (a[0] x^e1, a[1] x^e2): the factors are taken in with the tables' values
  // while the series is being summed, so they cost no time after it.
  Pair operator()(double x, Pair a) const noexcept {
    const auto bits = std::bit_cast<std::uint64_t>(x);
    // Biased exponent minus the lowest tabulated one; a negative x has the
    // sign bit above the exponent and lands out of range too.
    const std::uint64_t kk = (bits >> 52) - static_cast<std::uint64_t>(1023 + kMinExp);
    if (kk > static_cast<std::uint64_t>(kMaxExp - kMinExp)) {
      return a * Pair{std::pow(x, e1_), std::pow(x, e2_)};
    }
    const Entry& t = table_[static_cast<std::size_t>((bits >> 44) & 0xff)];
    const double m = std::bit_cast<double>((bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull);
    const double r = (m - t.m[0]) * t.m[1];
    const double r2 = r * r;
    const double r4 = r2 * r2;
    const Pair s = ((c_[0] + c_[1] * r) + r2 * (c_[2] + c_[3] * r)) +
                   r4 * ((c_[4] + c_[5] * r) + r2 * (c_[6] + c_[7] * r));
    return ((a * p2_[static_cast<std::size_t>(kk)]) * t.m0_e) * s;
  }

 private:
  struct Entry {
    Pair m;     // m0, 1 / m0
    Pair m0_e;  // m0^e1, m0^e2
  };
  double e1_, e2_;
  std::array<Entry, kTable> table_{};
  std::array<Pair, kTerms> c_{};
  std::vector<Pair> p2_;  // (2^(k e1), 2^(k e2)) from k = kMinExp
};

}  // namespace smc::machining::detail
