// Semi-discretization: the exact Tlusty-Tobias benchmark, the paper's case,
// convergence, the eigenvalue solver, and the lobe continuation.

#include "smc/machining/lobes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "sdm.hpp"  // internal: the dense check of the Arnoldi iteration
#include "smc/machining/paper_case.hpp"

namespace mc = smc::machining;
using std::numbers::pi;

namespace {

// A single mode along x under a cut whose force keeps its direction (as in
// turning): F_x = -a K_f (x(t) - x(t - tau)), tau = one spindle period.
struct Turning {
  double omega_n = 2 * pi * 500;  // rad/s
  double zeta = 0.03;
  double k = 2e4;     // N/mm
  double k_f = 2000;  // N/mm^2 (N per mm of chip per mm of depth)
};

// Closed-form Tlusty-Tobias boundary: lobe j, parametrised by the chatter
// frequency ratio r = omega / omega_n > 1:
//   G = 1 / (k (1 - r^2 + 2 i zeta r)),  a = -1 / (2 K_f Re G),
//   omega tau = 2 atan2(-Re G, Im G) + 2 pi j.
struct TtPoint {
  double tau_s, depth_mm;
};
TtPoint tlusty_tobias(const Turning& t, int lobe, double r) {
  const std::complex<double> g = 1.0 / (t.k * std::complex<double>(1 - r * r, 2 * t.zeta * r));
  const double depth = -1 / (2 * t.k_f * g.real());
  const double theta = 2 * std::atan2(-g.real(), g.imag()) + 2 * pi * lobe;
  return {theta / (r * t.omega_n), depth};
}

// The lowest closed-form boundary at delay tau: on each lobe, r such that
// tau_j(r) = tau (tau_j decreases with r), then the smallest depth.
double tlusty_tobias_at(const Turning& t, double tau) {
  double best = std::numeric_limits<double>::infinity();
  for (int j = 0; j < 60; ++j) {
    double lo = 1 + 1e-9, hi = 20;
    if (tlusty_tobias(t, j, lo).tau_s < tau || tlusty_tobias(t, j, hi).tau_s > tau) continue;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (tlusty_tobias(t, j, mid).tau_s > tau ? lo : hi) = mid;
    }
    best = std::min(best, tlusty_tobias(t, j, 0.5 * (lo + hi)).depth_mm);
  }
  return best;
}

mc::LinearisedCut turning_cut(const Turning& t, double tau, double depth) {
  mc::LinearisedCut c;
  c.structure.tool_x = {mc::Mode{t.omega_n, t.zeta, t.k}};
  c.period_s = tau;
  c.delay_periods = 1;
  c.mean_directional = [kf = t.k_f, depth](double, double) {
    return std::array<double, 4>{depth * kf, 0, 0, 0};
  };
  return c;
}

// The smallest depth at which the semi-discretised cut is unstable.
double sdm_turning_limit(const Turning& t, double tau, int intervals) {
  double lo = 1e-3, hi = lo;
  while (mc::dominant_multiplier(turning_cut(t, tau, hi), intervals).magnitude < 1) {
    lo = hi;
    hi *= 1.5;
  }
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    (mc::dominant_multiplier(turning_cut(t, tau, mid), intervals).magnitude < 1 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

TEST(TlustyTobias, LobesEqualTheClosedFormBoundaryWithinOnePercent) {
  const Turning t;
  // Speeds on lobes 0 to 4: f_n tau = 1.3, 1.8, 2.4, 3.7, 5.2 periods.
  for (const double periods : {1.3, 1.8, 2.4, 3.7, 5.2}) {
    const double tau = periods / 500.0;
    const double exact = tlusty_tobias_at(t, tau);
    const double sdm = sdm_turning_limit(t, tau, 40);
    EXPECT_NEAR(sdm, exact, 0.01 * exact) << "f_n tau = " << periods << " (" << 60 / tau << " rpm)";
  }
}

TEST(TlustyTobias, AbsoluteMinimumIsTwoKZetaOnePlusZetaOverKf) {
  const Turning t;
  const double a_lim = 2 * t.k * t.zeta * (1 + t.zeta) / t.k_f;  // 0.618 mm
  // The minimum of lobe j is at r = sqrt(1 + 2 zeta).
  const double r = std::sqrt(1 + 2 * t.zeta);
  for (const int lobe : {0, 1, 3}) {
    const TtPoint p = tlusty_tobias(t, lobe, r);
    EXPECT_NEAR(p.depth_mm, a_lim, 1e-9 * a_lim);  // the closed form itself
    EXPECT_NEAR(sdm_turning_limit(t, p.tau_s, 40), a_lim, 0.01 * a_lim) << "lobe " << lobe;
  }
}

TEST(PaperCase, TwoMillimetresUnstableOneMillimetreStableBySemiDiscretization) {
  const mc::MillingModel m = mc::paper_case();
  EXPECT_GT(mc::dominant_multiplier(m, {1500, 0.1, 2.0}).magnitude, 1.0);
  EXPECT_LT(mc::dominant_multiplier(m, {1500, 0.1, 1.0}).magnitude, 1.0);
  const mc::LobePoint p = mc::critical_depth_sdm(m, 1500, 0.1);
  EXPECT_EQ(p.kind, mc::BoundaryKind::hopf);
  EXPECT_GT(p.base_chatter_frequency_hz, 0);
  EXPECT_LE(p.base_chatter_frequency_hz, 50);  // half the tooth passing frequency
}

TEST(Convergence, ExtrapolatedRadiusConvergesInTheIntervals) {
  const mc::MillingModel m = mc::paper_case();
  mc::SdmOptions base;  // automatic m, extrapolated
  mc::SdmOptions fine;
  fine.intervals = 4 * mc::sdm_intervals(m, 1500, base);
  const double d_base = mc::critical_depth_sdm(m, 1500, 0.1, base).critical_depth_mm;
  const double d_fine = mc::critical_depth_sdm(m, 1500, 0.1, fine).critical_depth_mm;
  EXPECT_LT(std::abs(d_base - d_fine) / d_fine, 0.005) << d_base << " vs " << d_fine;
  // Without extrapolation the same m is visibly worse: the extrapolation is
  // what makes the default accurate.
  mc::SdmOptions plain = base;
  plain.extrapolate = false;
  plain.intervals = mc::sdm_intervals(m, 1500, base);
  const double d_plain = mc::critical_depth_sdm(m, 1500, 0.1, plain).critical_depth_mm;
  EXPECT_GT(std::abs(d_plain - d_fine), std::abs(d_base - d_fine));
}

TEST(Eigenvalues, ArnoldiFindsTheDenseSpectralRadius) {
  const mc::MillingModel m = mc::paper_case();
  for (const double rpm : {900.0, 1500.0, 2600.0}) {
    const double period = mc::tooth_period_s(rpm, 4);
    smc::machining::detail::SdmSystem sys(m.structure, period, 1, 30);
    // A periodic directional matrix like a milling cut's.
    std::vector<smc::machining::detail::Mat2> h(30);
    for (int i = 0; i < 30; ++i) {
      const double th = 2 * pi * (i + 0.5) / 30;
      h[static_cast<std::size_t>(i)] = {6000 + 3000 * std::cos(th), 2000 * std::sin(th),
                                        -4000 + 1000 * std::sin(th), 9000 + 2000 * std::cos(th)};
    }
    const mc::Multiplier a = sys.dominant(h);
    const mc::Multiplier d = sys.dominant_dense(h);
    EXPECT_NEAR(a.magnitude, d.magnitude, 1e-8 * d.magnitude) << rpm;
  }
}

TEST(Lobes, ContinuationFindsTheLowestBoundaryAtEverySpeed) {
  const mc::MillingModel m = mc::paper_case();
  mc::LobeOptions o;
  o.rpm_min = 1300;
  o.rpm_max = 2300;
  o.speeds = 21;
  o.feed_per_tooth_mm = 0.1;
  int calls = 0;
  o.on_progress = [&calls](int done, int total) {
    ++calls;
    EXPECT_EQ(total, 21);
    EXPECT_EQ(done, calls);
  };
  const std::vector<mc::LobePoint> lobes = mc::stability_lobes(m, o);
  ASSERT_EQ(lobes.size(), 21u);
  EXPECT_EQ(calls, 21);
  for (std::size_t i = 0; i < lobes.size(); i += 7) {
    const mc::LobePoint alone = mc::critical_depth_sdm(m, lobes[i].spindle_rpm, 0.1);
    EXPECT_NEAR(lobes[i].critical_depth_mm, alone.critical_depth_mm, 2e-3 * alone.critical_depth_mm)
        << lobes[i].spindle_rpm << " rpm";
  }
}

TEST(Lobes, RejectsBadArguments) {
  const mc::MillingModel m = mc::paper_case();
  mc::LobeOptions o;
  o.rpm_min = 2000;
  o.rpm_max = 1000;
  o.feed_per_tooth_mm = 0.1;
  EXPECT_THROW(mc::stability_lobes(m, o), std::invalid_argument);
  EXPECT_THROW(mc::critical_depth_sdm(m, 1500, 0.0), std::invalid_argument);  // power law, no chip
  mc::SdmOptions bad;
  bad.relative_tolerance = 0;
  EXPECT_THROW(mc::critical_depth_sdm(m, 1500, 0.1, bad), std::invalid_argument);
}
