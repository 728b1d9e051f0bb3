// Cutter runout and tooth-to-tooth variation (README.md, "Runout").

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "smc/machining/cutting.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/simulator.hpp"
#include "smc/machining/tds.hpp"
#include "smc_config.pb.h"
#include "test_models.hpp"

namespace mc = smc::machining;

namespace {

// Largest |F| while each tooth is alone in the cut, over one revolution of a
// rigid cut (vibration negligible: the kinematics alone). The part is 10 mm
// wide and centred, so one tooth at a time is in it.
std::vector<double> peak_per_tooth(mc::MillingModel m, double fpt) {
  m.workpiece.width_mm = 10;
  m.workpiece.offset_mm = 0;
  const int n = m.cutter.teeth;
  std::vector<double> peak(static_cast<size_t>(n), 0.0);
  const double rev = 2 * std::numbers::pi;
  for (int j = 0; j < 3600; ++j) {
    const double a = rev * j / 3600;
    const mc::CutForces f = mc::static_forces(m, {1500, fpt, 1.0}, a);
    if (f.teeth_in_cut != 1) continue;
    int tooth = 0;  // the one nearest theta = 0 (the middle of the part)
    for (int i = 1; i < n; ++i) {
      if (std::cos(a + rev * i / n) > std::cos(a + rev * tooth / n)) tooth = i;
    }
    auto& p = peak[static_cast<size_t>(tooth)];
    p = std::max(p, std::hypot(f.fx_n, f.fy_n));
  }
  return peak;
}

}  // namespace

TEST(Runout, TheChipOfEachToothFollowsTheKinematics) {
  const double r[] = {0.010, 0, -0.010, 0};  // mm: eccentric, 10 um
  const double f = 0.1;
  // At theta = 0 (cos 1): tooth 0 cuts f + r0 - r3, tooth 2 f + r2 - r1.
  EXPECT_NEAR(mc::runout_chip_mm(r, 4, 0, f, 1.0), 0.110, 1e-12);
  EXPECT_NEAR(mc::runout_chip_mm(r, 4, 1, f, 1.0), 0.090, 1e-12);
  EXPECT_NEAR(mc::runout_chip_mm(r, 4, 2, f, 1.0), 0.090, 1e-12);
  EXPECT_NEAR(mc::runout_chip_mm(r, 4, 3, f, 1.0), 0.110, 1e-12);
  // Over a revolution the chips sum to teeth x feed: runout moves material
  // between teeth, it does not add any.
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += mc::runout_chip_mm(r, 4, i, f, 1.0);
  EXPECT_NEAR(sum, 4 * f, 1e-12);
  // A tooth short by more than a feed cuts nothing; the next one takes what
  // two feeds left.
  const double big[] = {0, -0.150, 0, 0};
  EXPECT_LT(mc::runout_chip_mm(big, 4, 1, f, 1.0), 0);
  EXPECT_NEAR(mc::runout_chip_mm(big, 4, 2, f, 1.0), 2 * f + 0 - 0.0, 1e-12)
      << "tooth 2 removes what tooth 0 left, two feeds back";
  // Without runout: f cos(theta).
  const double none[] = {0, 0, 0, 0};
  EXPECT_DOUBLE_EQ(mc::runout_chip_mm(none, 4, 3, f, 0.5), 0.05);
}

TEST(Runout, EccentricMountingGivesACosineOverTheTeeth) {
  const auto r = mc::eccentric_runout_um(4, 10, 0);
  ASSERT_EQ(r.size(), 4u);
  EXPECT_NEAR(r[0], 10, 1e-12);
  EXPECT_NEAR(r[1], 0, 1e-12);
  EXPECT_NEAR(r[2], -10, 1e-12);
  EXPECT_NEAR(r[3], 0, 1e-12);
  const auto q = mc::eccentric_runout_um(4, 10, 90);
  EXPECT_NEAR(q[1], 10, 1e-12);
  EXPECT_THROW((void)mc::eccentric_runout_um(0, 10), std::invalid_argument);
  EXPECT_THROW((void)mc::eccentric_runout_um(4, std::nan("")), std::invalid_argument);
}

// On a rigid cut the tooth that stands out cuts the thicker chip: the per
// tooth peak force follows chip^(1 + feed exponent).
TEST(Runout, TheToothThatStandsOutCutsMore) {
  mc::MillingModel m = mc::test::rigid_paper_case();
  const auto even = peak_per_tooth(m, 0.1);
  for (double p : even) EXPECT_NEAR(p, even[0], 1e-6 * even[0]);
  m.cutter.radial_runout_um = mc::eccentric_runout_um(4, 10, 0);
  const auto uneven = peak_per_tooth(m, 0.1);
  EXPECT_GT(uneven[0], 1.05 * even[0]) << "tooth 0 stands out by 10 um: chip 0.11 mm";
  EXPECT_LT(uneven[2], 0.95 * even[0]) << "tooth 2 is short: chip 0.09 mm";
  // Chips 0.11 and 0.09 mm: F ~ h^(1 + feed exponent), a ratio above 1.1.
  EXPECT_GT(uneven[0] / uneven[2], 1.1);
}

TEST(Runout, WithoutItTheSimulationIsUnchangedBitForBit) {
  const mc::MillingModel plain = mc::paper_case();
  mc::MillingModel zeros = plain;
  zeros.cutter.radial_runout_um = {0, 0, 0, 0};
  mc::MillSimulator a(plain), b(zeros);
  mc::Sample sa, sb;
  for (int k = 0; k < 4000; ++k) {
    a.step({10, 1500, 1.0}, sa);
    b.step({10, 1500, 1.0}, sb);
    ASSERT_EQ(sa.fx_n, sb.fx_n) << k;
    ASSERT_EQ(sa.fy_n, sb.fy_n) << k;
    ASSERT_EQ(sa.fz_n, sb.fz_n) << k;
  }
}

// The stepping simulator with runout: each revolution repeats (the teeth
// differ), and the forces differ from tooth to tooth.
TEST(Runout, TheSimulatedForceRepeatsEveryRevolutionNotEveryTooth) {
  mc::MillingModel m = mc::test::rigid_paper_case();
  m.cutter.radial_runout_um = mc::eccentric_runout_um(4, 20, 0);
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 30;  // the whole cutter over the part
  mc::MillSimulator sim(m, o);
  mc::Sample s;
  std::vector<double> fy;
  for (int k = 0; k < 400; ++k) {  // 0.2 s: 5 revolutions at 1500 rpm
    sim.step({10, 1500, 1.0}, s);
    fy.push_back(s.fy_n);
  }
  // 80 samples a revolution, 20 a tooth period.
  double rev_diff = 0, tooth_diff = 0, scale = 0;
  for (size_t k = 200; k < 320; ++k) {
    rev_diff = std::max(rev_diff, std::fabs(fy[k] - fy[k + 80]));
    tooth_diff = std::max(tooth_diff, std::fabs(fy[k] - fy[k + 20]));
    scale = std::max(scale, std::fabs(fy[k]));
  }
  ASSERT_GT(scale, 10);
  EXPECT_LT(rev_diff, 1e-3 * scale);
  EXPECT_GT(tooth_diff, 0.05 * scale);
}

TEST(Runout, BadValuesAreRefusedNamingTheTooth) {
  mc::MillingModel m = mc::paper_case();
  m.cutter.radial_runout_um = {1, 2, 3};
  auto errors = mc::validation_errors(m, "model");
  ASSERT_FALSE(errors.empty());
  EXPECT_NE(errors[0].find("model.cutter.radial_runout_um: needs one value per tooth (4)"),
            std::string::npos)
      << errors[0];
  m.cutter.radial_runout_um = {0, std::nan(""), 0, 2000};
  errors = mc::validation_errors(m, "model");
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("radial_runout_um[1]"), std::string::npos) << errors[0];
  EXPECT_NE(errors[1].find("radial_runout_um[3]"), std::string::npos) << errors[1];
  EXPECT_THROW(mc::MillSimulator bad(m), std::invalid_argument);
}

TEST(Runout, TravelsThroughTheDocument) {
  mc::MillingModel m = mc::paper_case();
  m.cutter.radial_runout_um = mc::eccentric_runout_um(4, 15, 30);
  const auto back = mc::from_proto(mc::to_proto(m), "m");
  EXPECT_EQ(back.cutter.radial_runout_um, m.cutter.radial_runout_um);
}

// A steady cut's stability is judged without the runout (its chatter-free
// motion repeats only every revolution and has no orbit to start the
// criterion on; README.md, "Runout"), and the reason says so; a run from
// rest with runout compares the state once per revolution.
TEST(Runout, SteadyCutVerdictsLeaveItOutAndSaySo) {
  const mc::MillingModel plain = mc::paper_case();
  mc::MillingModel ro = plain;
  ro.cutter.radial_runout_um = mc::eccentric_runout_um(4, 10, 0);
  const auto a = mc::critical_depth_tds(plain, 1500, 0.1);
  const auto b = mc::critical_depth_tds(ro, 1500, 0.1);
  EXPECT_EQ(b.critical_depth_mm, a.critical_depth_mm);
  const auto v = mc::assess_stability(ro, {1500, 0.1, 1.0});
  EXPECT_EQ(v.verdict, mc::Verdict::stable) << v.reason;
  EXPECT_NE(v.reason.find("judged without the cutter's runout"), std::string::npos) << v.reason;
  mc::BatchOptions o;
  o.steady = true;
  o.duration_s = 1.0;
  o.record_every_s = 0;
  const auto r = mc::simulate(ro, {1500, 0.1, 1.0}, o);
  EXPECT_EQ(r.stability.verdict, mc::Verdict::stable) << r.stability.reason;
  EXPECT_NE(r.stability.reason.find("revolution"), std::string::npos) << r.stability.reason;
}

// Tool condition (MillSimulator::set_tooth_runout_mm, set_force_scale): a
// tooth that loses its edge cuts nothing and the next tooth takes its chip
// too; the material removed per revolution, and so the mean force, stays
// about the same while the peak rises; wear scales every pressure. Rigid
// cut, steady feed, the whole cutter over the part.
TEST(ToolCondition, ALostEdgeMovesItsChipToTheNextToothAndWearScalesTheForce) {
  const mc::MillingModel m = mc::test::rigid_paper_case();
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 30;
  mc::MillSimulator sim(m, o);
  mc::Sample s;
  // One revolution (80 samples at 1500 rpm) after `settle` samples: peak
  // and mean |F_y|, and the teeth cutting at a quarter turn apart.
  auto revolution = [&](int settle, double& peak, double& mean) {
    for (int k = 0; k < settle; ++k) sim.step({10, 1500, 1.0}, s);
    peak = mean = 0;
    for (int k = 0; k < 80; ++k) {
      sim.step({10, 1500, 1.0}, s);
      peak = std::max(peak, std::fabs(s.fy_n));
      mean += std::fabs(s.fy_n) / 80;
    }
  };
  double peak0 = 0, mean0 = 0;
  revolution(160, peak0, mean0);
  sim.set_tooth_runout_mm(1, sim.tooth_runout_mm(1) - 1.0);  // tooth 2 loses its edge
  double peak1 = 0, mean1 = 0;
  revolution(160, peak1, mean1);
  // The follower's chip doubles: F ~ h^(1 + feed exponent) = 2^0.63 = 1.55.
  EXPECT_GT(peak1, 1.3 * peak0) << peak0 << " -> " << peak1;
  EXPECT_NEAR(mean1 / mean0, 1.0, 0.25) << "the same material per revolution";
  sim.set_force_scale(1.2);
  double peak2 = 0, mean2 = 0;
  revolution(160, peak2, mean2);
  EXPECT_NEAR(peak2 / peak1, 1.2, 0.01);
  EXPECT_NEAR(mean2 / mean1, 1.2, 0.01);
  sim.reset();
  EXPECT_DOUBLE_EQ(sim.tooth_runout_mm(1), -1.0) << "a new part does not mend the tool";
}
