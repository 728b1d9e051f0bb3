// Cutting forces without vibration against a hand computation from the
// paper's A1-A4 (and the axial force of DOMAIN.md note 3), engagement
// geometry, immersion function, power and tangent stiffness.

#include "smc/machining/cutting.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fast_pow.hpp"  // internal
#include "smc/machining/paper_case.hpp"
#include "smc/machining/simulator.hpp"
#include "test_models.hpp"

namespace mc = smc::machining;
using std::numbers::pi;

namespace {

struct Hand {
  double fx_n = 0, fy_n = 0, fz_n = 0, power_w = 0;
};

// The paper's A1-A4 written out for the teeth at the given angles (degrees),
// all assumed in cut: P in kN/mm^2, f_i = f cos(theta) and d in mm, V in
// m/min; forces in kN converted to N. A3 and A4 with the lead angle psi_r;
// F_z = P_T f_i d sin(psi_r); power = sum P_C f_i d V.
Hand hand_a1_a4(std::initializer_list<double> teeth_deg, double f, double d, double rpm,
                double radius_mm, double lead_deg) {
  Hand h;
  const double v = 2 * pi * radius_mm / 1000 * rpm;  // m/min
  const double psi = lead_deg * pi / 180;
  for (const double deg : teeth_deg) {
    const double th = deg * pi / 180;
    const double fi = f * std::cos(th);
    const double pc = 0.29 * std::pow(fi, -0.25) * std::pow(d, -0.13) * std::pow(v / 1000, -0.72);
    const double pt = 0.16 * std::pow(fi, -0.40) * std::pow(d, -0.41) * std::pow(v / 1000, -0.58);
    h.fx_n += 1000 * (-pt * fi * d * std::cos(psi) * std::cos(th) + pc * fi * d * std::sin(th));
    h.fy_n += 1000 * (-pt * fi * d * std::cos(psi) * std::sin(th) - pc * fi * d * std::cos(th));
    h.fz_n += 1000 * pt * fi * d * std::sin(psi);
    h.power_w += 1000 * pc * fi * d * v / 60;
  }
  return h;
}

}  // namespace

TEST(StaticForces, EqualA1ToA4AtSeveralToothAngles) {
  const mc::MillingModel m = mc::paper_case();    // 4 teeth, 25 mm, lead 15 deg, 48 mm centred
  ASSERT_EQ(mc::rotation_sense(m.workpiece), 1);  // the paper's sense: theta grows
  const mc::CutConditions cut{1500, 0.1, 2.0};
  // Tooth 0 at these angles; teeth 90 degrees apart; in cut within +-73.7 deg.
  struct Case {
    double angle_deg;
    std::initializer_list<double> in_cut_deg;
  };
  for (const Case& c : {Case{0, {0}}, Case{30, {30, -60}}, Case{-45, {-45, 45}},
                        Case{60, {60, -30}}, Case{72, {72, -18}}}) {
    const mc::CutForces f = mc::static_forces(m, cut, c.angle_deg * pi / 180);
    const Hand h = hand_a1_a4(c.in_cut_deg, 0.1, 2.0, 1500, 25, 15);
    EXPECT_NEAR(f.fx_n, h.fx_n, 1e-9 * std::abs(h.fy_n)) << c.angle_deg;
    EXPECT_NEAR(f.fy_n, h.fy_n, 1e-9 * std::abs(h.fy_n)) << c.angle_deg;
    EXPECT_NEAR(f.fz_n, h.fz_n, 1e-9 * std::abs(h.fz_n)) << c.angle_deg;
    EXPECT_NEAR(f.power_w, h.power_w, 1e-9 * h.power_w) << c.angle_deg;
    EXPECT_EQ(f.teeth_in_cut, static_cast<int>(c.in_cut_deg.size())) << c.angle_deg;
  }
}

TEST(StaticForces, SimulatorWithoutVibrationMatchesTheHandComputation) {
  // A structure a million times stiffer: the chip is the nominal one, so the
  // simulated forces must be A1-A4 at the tooth angles of each sample.
  const mc::MillingModel m = mc::test::rigid_paper_case();
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 20;  // fully over the part
  mc::MillSimulator sim(m, o);
  mc::Sample s;
  const double rpm = 1500;
  double mean_fx = 0, mean_fy = 0, mean_fz = 0, mean_p = 0;
  const int samples = 80;  // two revolutions of 0.5 ms samples
  for (int k = 1; k <= samples; ++k) {
    ASSERT_EQ(sim.step({10, rpm, 2.0}, s), 0u);
    // Tooth 0 at theta = Omega t; hand-compute the teeth in cut.
    const double angle = std::remainder(2 * pi * rpm / 60 * s.time_s, 2 * pi);
    const double limit = std::asin(24.0 / 25.0);
    std::vector<double> in_cut;
    for (int i = 0; i < 4; ++i) {
      const double th = std::remainder(angle + i * pi / 2, 2 * pi);
      if (std::abs(th) <= limit) in_cut.push_back(th * 180 / pi);
    }
    Hand h;
    for (const double deg : in_cut) {
      const Hand one = hand_a1_a4({deg}, 0.1, 2.0, rpm, 25, 15);
      h.fx_n += one.fx_n;
      h.fy_n += one.fy_n;
      h.fz_n += one.fz_n;
      h.power_w += one.power_w;
    }
    EXPECT_NEAR(s.fx_n, h.fx_n, 1e-5 * 300) << "sample " << k;
    EXPECT_NEAR(s.fy_n, h.fy_n, 1e-5 * 300) << "sample " << k;
    EXPECT_NEAR(s.fz_n, h.fz_n, 1e-5 * 300) << "sample " << k;
    EXPECT_NEAR(s.power_w, h.power_w, 1e-5 * 1500) << "sample " << k;
    mean_fx += s.fx_n / samples;
    mean_fy += s.fy_n / samples;
    mean_fz += s.fz_n / samples;
    mean_p += s.power_w / samples;
  }
  // The mean over two revolutions of samples (20 per tooth period) against
  // the mean of the hand computation at the same angles is implied above;
  // against the exact period mean, within the sampling error.
  const mc::CutForces exact = mc::mean_static_forces(m, mc::CutConditions{rpm, 0.1, 2.0});
  EXPECT_NEAR(mean_fx, exact.fx_n, 0.02 * std::abs(exact.fy_n));
  EXPECT_NEAR(mean_fy, exact.fy_n, 0.02 * std::abs(exact.fy_n));
  EXPECT_NEAR(mean_fz, exact.fz_n, 0.02 * exact.fz_n);
  EXPECT_NEAR(mean_p, exact.power_w, 0.02 * exact.power_w);
}

TEST(Engagement, EntryAndExitFromWidthAndOffset) {
  mc::Cutter c{4, 25, 0};
  // Centred, 48 mm wide: +-asin(24/25); the teeth enter on -y.
  mc::Engagement e = mc::engagement(c, mc::Workpiece{48, 0, 100, false});
  ASSERT_TRUE(e.engaged);
  EXPECT_NEAR(e.entry_rad, -std::asin(0.96), 1e-12);
  EXPECT_NEAR(e.exit_rad, std::asin(0.96), 1e-12);
  EXPECT_NEAR(e.mean_teeth_in_cut, 2 * std::asin(0.96) * 4 / (2 * pi), 1e-12);
  // Wider than the cutter: half a revolution.
  e = mc::engagement(c, mc::Workpiece{80, 0, 100, false});
  EXPECT_NEAR(e.low_rad, -pi / 2, 1e-12);
  EXPECT_NEAR(e.high_rad, pi / 2, 1e-12);
  // A 20 mm part on the +y side, up-milling: the teeth enter at the part's
  // outer edge... of the band at y = 20 (theta = asin 0.8) and leave at y = 0.
  e = mc::engagement(c, mc::Workpiece{20, 10, 100, false});
  EXPECT_EQ(mc::rotation_sense(mc::Workpiece{20, 10, 100, false}), -1);
  EXPECT_NEAR(e.entry_rad, std::asin(0.8), 1e-12);
  EXPECT_NEAR(e.exit_rad, 0, 1e-12);
  // The same part down-milled: enter at the front (largest chip), leave at the edge.
  e = mc::engagement(c, mc::Workpiece{20, 10, 100, true});
  EXPECT_EQ(mc::rotation_sense(mc::Workpiece{20, 10, 100, true}), 1);
  EXPECT_NEAR(e.entry_rad, 0, 1e-12);
  EXPECT_NEAR(e.exit_rad, std::asin(0.8), 1e-12);
  // End milling from the edge (a/D = 0.1) on the -y side, down-milling: the
  // chip goes to zero at the exit (theta = -pi/2).
  e = mc::engagement(c, mc::Workpiece{5, -22.5, 100, true});
  EXPECT_NEAR(e.exit_rad, -pi / 2, 1e-12);
  EXPECT_NEAR(std::cos(e.exit_rad), 0, 1e-12);
  EXPECT_GT(std::cos(e.entry_rad), 0.4);
  // A band beside the cutter never cuts.
  EXPECT_FALSE(mc::engagement(c, mc::Workpiece{10, 40, 100, false}).engaged);
}

TEST(Engagement, ImmersionFunctionA5) {
  const mc::Engagement e = mc::engagement(mc::Cutter{4, 25, 0}, mc::Workpiece{48, 0, 100, false});
  EXPECT_TRUE(mc::in_cut(e, 0));
  EXPECT_TRUE(mc::in_cut(e, 1.2));
  EXPECT_TRUE(mc::in_cut(e, 2 * pi - 1.2));  // A5's theta >= theta_en with angles in [0, 2 pi)
  EXPECT_FALSE(mc::in_cut(e, 1.4));
  EXPECT_FALSE(mc::in_cut(e, pi));
  EXPECT_TRUE(mc::in_cut(e, 4 * pi + 0.3));
  EXPECT_FALSE(mc::in_cut(e, std::nan("")));
}

TEST(ToothLoad, LinearLawAndLeadAngle) {
  const mc::CuttingLaw law = mc::LinearLaw{600, 200, 50};
  const mc::ToothLoad l = mc::tooth_load(law, 30, 0.05, 2.0, 100);
  EXPECT_DOUBLE_EQ(l.tangential_n, 600 * 2.0 * 0.05);
  EXPECT_NEAR(l.radial_n, 200 * 2.0 * 0.05 * std::cos(pi / 6), 1e-12);
  EXPECT_NEAR(l.axial_n, 200 * 2.0 * 0.05 * std::sin(pi / 6) + 50 * 2.0 * 0.05, 1e-12);
  EXPECT_EQ(mc::tooth_load(law, 0, -0.01, 2.0, 100).tangential_n, 0);  // out of the material
  EXPECT_EQ(mc::tooth_load(law, 0, 0.01, 0.0, 100).tangential_n, 0);   // no depth
}

TEST(ToothLoad, TangentStiffnessIsTheChipDerivative) {
  const mc::MillingModel m = mc::paper_case();
  for (const double chip : {0.02, 0.07, 0.1}) {
    const double dh = 1e-6 * chip;
    const auto up = mc::tooth_load(m.law, 15, chip + dh, 1.5, 235.6);
    const auto dn = mc::tooth_load(m.law, 15, chip - dh, 1.5, 235.6);
    const mc::CuttingStiffness k = mc::tangent_stiffness(m.law, 15, chip, 1.5, 235.6);
    EXPECT_NEAR(k.tangential_n_per_mm, (up.tangential_n - dn.tangential_n) / (2 * dh),
                1e-6 * k.tangential_n_per_mm);
    EXPECT_NEAR(k.radial_n_per_mm, (up.radial_n - dn.radial_n) / (2 * dh),
                1e-6 * k.radial_n_per_mm);
    EXPECT_NEAR(k.axial_n_per_mm, (up.axial_n - dn.axial_n) / (2 * dh), 1e-6 * k.axial_n_per_mm);
    // For the power law the secant (average) stiffness F/h is smaller:
    // (1 + feed exponent) = 0.75 of the tangent's inverse ratio.
    const auto at = mc::tooth_load(m.law, 15, chip, 1.5, 235.6);
    EXPECT_NEAR(k.tangential_n_per_mm, 0.75 * at.tangential_n / chip, 1e-9 * at.tangential_n);
  }
}

TEST(Power, IsTangentialForceTimesCuttingSpeed) {
  EXPECT_NEAR(mc::cutting_speed_m_per_min(25, 1500), 2 * pi * 0.025 * 1500, 1e-12);
  const mc::MillingModel m = mc::paper_case();
  const mc::CutForces f = mc::static_forces(m, mc::CutConditions{1500, 0.1, 2}, 0.0);
  const mc::ToothLoad l = mc::tooth_load(m.law, 15, 0.1, 2, mc::cutting_speed_m_per_min(25, 1500));
  EXPECT_NEAR(f.power_w, l.tangential_n * mc::cutting_speed_m_per_s(25, 1500), 1e-9);
  EXPECT_NEAR(f.torque_n_m, l.tangential_n * 0.025, 1e-12);
}

TEST(FastPow, MatchesStdPowToAFewUlp) {
  // The simulator's shared-decomposition power (src/fast_pow.hpp) for the
  // paper's exponents 1 + a: 0.75 (cutting) and 0.6 (thrust).
  const smc::machining::detail::PowPair pow2(0.75, 0.6);
  double worst = 0;
  double x = 1e-9;
  while (x < 100) {
    double a, b;
    pow2(x, a, b);
    worst =
        std::max({worst, std::abs(a / std::pow(x, 0.75) - 1), std::abs(b / std::pow(x, 0.6) - 1)});
    x *= 1.0 + 1.0 / 1021.0;  // visits every mantissa bucket many times
  }
  EXPECT_LT(worst, 2e-15);
  // Outside the tables: the std::pow fallback.
  double a, b;
  pow2(1e-30, a, b);
  EXPECT_DOUBLE_EQ(a, std::pow(1e-30, 0.75));
  pow2(0.0, a, b);
  EXPECT_EQ(a, 0.0);
}
