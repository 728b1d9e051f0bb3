// Time-domain stability: the paper's case, step-halving convergence, the
// stability criterion against the semi-discretization, the periodic start.

#include "smc/machining/tds.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "smc/machining/lobes.hpp"
#include "smc/machining/paper_case.hpp"
#include "test_models.hpp"

namespace mc = smc::machining;

namespace {
constexpr double kPaperRpm = 1500;
constexpr double kPaperFeed = 0.1;  // 10 mm/s at 1500 rpm with 4 teeth
}  // namespace

TEST(PaperCase, TwoMillimetresChatterOneMillimetreIsStableInTheTimeDomain) {
  const mc::MillingModel m = mc::paper_case();
  const mc::StabilityReport two = mc::assess_stability(m, {kPaperRpm, kPaperFeed, 2.0});
  const mc::StabilityReport one = mc::assess_stability(m, {kPaperRpm, kPaperFeed, 1.0});
  EXPECT_EQ(two.verdict, mc::Verdict::unstable) << two.reason;
  EXPECT_EQ(one.verdict, mc::Verdict::stable) << one.reason;
  // Also from rest, as a machine would start the cut, judged from the
  // saturated chatter of the full nonlinear model.
  mc::BatchOptions o;
  o.duration_s = 1.0;
  o.record_every_s = 0;
  EXPECT_EQ(mc::simulate(m, {kPaperRpm, kPaperFeed, 2.0}, o).stability.verdict,
            mc::Verdict::unstable);
  const mc::BatchResult r1 = mc::simulate(m, {kPaperRpm, kPaperFeed, 1.0}, o);
  EXPECT_EQ(r1.stability.verdict, mc::Verdict::stable) << r1.stability.reason;
  EXPECT_TRUE(r1.stability.settled);
}

TEST(PaperCase, TimeDomainAndSemiDiscretizationAgreeAt1500Rpm) {
  const mc::MillingModel m = mc::paper_case();
  const mc::TdsSearchResult tds = mc::critical_depth_tds(m, kPaperRpm, kPaperFeed);
  const mc::LobePoint sdm = mc::critical_depth_sdm(m, kPaperRpm, kPaperFeed);
  ASSERT_TRUE(tds.bounded);
  // The documented default geometry: between the 1 mm and 2 mm passes.
  EXPECT_GT(tds.critical_depth_mm, 1.0);
  EXPECT_LT(tds.critical_depth_mm, 2.0);
  EXPECT_GT(sdm.critical_depth_mm, 1.0);
  EXPECT_LT(sdm.critical_depth_mm, 2.0);
  // Required: within 10 %. Both estimate the same boundary (the stability of
  // the periodic cut), so they agree much better; 2 % guards against
  // regressions in either.
  const double rel =
      std::abs(tds.critical_depth_mm - sdm.critical_depth_mm) / sdm.critical_depth_mm;
  EXPECT_LT(rel, 0.10);
  EXPECT_LT(rel, 0.02) << "TDS " << tds.critical_depth_mm << " mm, SDM " << sdm.critical_depth_mm
                       << " mm";
  // The search's bracket is honest.
  EXPECT_LE(tds.stable_depth_mm, tds.critical_depth_mm);
  EXPECT_GE(tds.unstable_depth_mm, tds.critical_depth_mm);
  EXPECT_LT(tds.unstable_depth_mm - tds.stable_depth_mm, 2e-3 * tds.critical_depth_mm);
}

TEST(Convergence, HalvingTheInternalStepChangesTheCriticalDepthByLessThanOnePercent) {
  const mc::MillingModel m = mc::paper_case();
  mc::TdsSearchOptions coarse;
  coarse.max_internal_step_s = 1e-5;
  coarse.relative_tolerance = 2e-4;
  mc::TdsSearchOptions fine = coarse;
  fine.max_internal_step_s = 0.5e-5;
  const double a = mc::critical_depth_tds(m, kPaperRpm, kPaperFeed, coarse).critical_depth_mm;
  const double b = mc::critical_depth_tds(m, kPaperRpm, kPaperFeed, fine).critical_depth_mm;
  EXPECT_LT(std::abs(a - b) / b, 0.01) << a << " mm at 1e-5 s, " << b << " mm at 5e-6 s";
}

TEST(Criterion, FollowsTheFloquetMultiplierAcrossTheBoundary) {
  const mc::MillingModel m = mc::paper_case();
  const mc::LobePoint sdm = mc::critical_depth_sdm(m, kPaperRpm, kPaperFeed);
  for (const double f : {0.97, 1.03}) {
    const double d = f * sdm.critical_depth_mm;
    const mc::StabilityReport s = mc::assess_stability(m, {kPaperRpm, kPaperFeed, d});
    EXPECT_EQ(s.verdict, f < 1 ? mc::Verdict::stable : mc::Verdict::unstable)
        << d << ": " << s.reason;
    const mc::Multiplier mu = mc::dominant_multiplier(m, {kPaperRpm, kPaperFeed, d});
    if (!std::isnan(s.multiplier)) {
      EXPECT_NEAR(s.multiplier, mu.magnitude, 0.03) << d;
    }
  }
}

TEST(Criterion, StartsOnThePeriodicMotionOfTheCut) {
  // Undisturbed, the computed periodic motion stays put even at an unstable
  // depth (until rounding errors grow): it is the cut's chatter-free motion.
  mc::BatchOptions o;
  o.duration_s = 0.05;  // five tooth periods
  o.start_on_steady_cut = true;
  o.disturbance_mm = 0;
  o.record_every_s = 0;
  const mc::BatchResult r = mc::simulate(mc::paper_case(), {kPaperRpm, kPaperFeed, 2.0}, o);
  ASSERT_EQ(r.section.size(), 5u);
  for (const double d : r.section) EXPECT_LT(d, 1e-12);
  // Travelling runs have no periodic motion to start on.
  o.steady = false;
  EXPECT_THROW(mc::simulate(mc::paper_case(), {kPaperRpm, kPaperFeed, 2.0}, o),
               std::invalid_argument);
}

TEST(Criterion, RevolutionDelayOptionAgreesToo) {
  mc::MillingModel m = mc::paper_case();
  m.delay = mc::DelayKind::spindle_revolution;
  const double tds = mc::critical_depth_tds(m, kPaperRpm, kPaperFeed).critical_depth_mm;
  const double sdm = mc::critical_depth_sdm(m, kPaperRpm, kPaperFeed).critical_depth_mm;
  EXPECT_LT(std::abs(tds - sdm) / sdm, 0.02) << tds << " vs " << sdm;
}

TEST(Criterion, InterruptedCutsWithFlipAndHopfBoundaries) {
  // Highly interrupted down-milling (a/D = 0.05, linear law): at 18,000 rpm
  // the boundary is a period doubling (flip), at 22,000 rpm a Hopf.
  const mc::MillingModel m = mc::test::insperger_1dof(0.05);
  for (const double rpm : {18000.0, 22000.0}) {
    const mc::LobePoint sdm = mc::critical_depth_sdm(m, rpm, 0.05);
    const mc::TdsSearchResult tds = mc::critical_depth_tds(m, rpm, 0.05);
    EXPECT_LT(std::abs(tds.critical_depth_mm - sdm.critical_depth_mm) / sdm.critical_depth_mm, 0.02)
        << rpm << " rpm: TDS " << tds.critical_depth_mm << ", SDM " << sdm.critical_depth_mm;
  }
}

TEST(Search, ReportsUnboundedResults) {
  mc::TdsSearchOptions o;
  o.max_depth_mm = 0.5;
  const mc::TdsSearchResult r = mc::critical_depth_tds(mc::paper_case(), kPaperRpm, kPaperFeed, o);
  EXPECT_FALSE(r.bounded);
  EXPECT_DOUBLE_EQ(r.critical_depth_mm, 0.5);
  EXPECT_THROW(mc::critical_depth_tds(mc::paper_case(), kPaperRpm, 0.0), std::invalid_argument);
  EXPECT_THROW(mc::critical_depth_tds(mc::paper_case(), -5, 0.1), std::invalid_argument);
}
