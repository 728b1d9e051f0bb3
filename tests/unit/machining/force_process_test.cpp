// The force-process model F_Y = K d^beta f^alpha (eq. 1): evaluation,
// inverse, least-squares fit with statistics.

#include "smc/machining/force_process.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "smc/machining/paper_case.hpp"

namespace mc = smc::machining;

TEST(ForceProcess, EvaluatesEquationOne) {
  const mc::ForceProcessModel m = mc::paper_force_process_model();
  // 0.76 * 2^0.65 * 0.1^0.63 kN, written out.
  const double expected = 1000 * 0.76 * std::pow(2.0, 0.65) * std::pow(0.1, 0.63);
  EXPECT_NEAR(m.force_n(2.0, 0.1), expected, 1e-9);
  EXPECT_NEAR(expected, 279.5, 0.1);
  EXPECT_NEAR(m.gain_kn(2.0), 0.76 * std::pow(2.0, 0.65), 1e-12);
  EXPECT_EQ(m.force_n(0, 0.1), 0);
  EXPECT_TRUE(std::isnan(m.force_n(-1, 0.1)));
  EXPECT_TRUE(std::isnan(m.force_n(1, std::nan(""))));
}

TEST(ForceProcess, InverseGivesTheFeedForATargetForce) {
  const mc::ForceProcessModel m = mc::paper_force_process_model();
  for (const double d : {0.5, 1.0, 2.0}) {
    for (const double target : {50.0, 190.0, 400.0}) {
      const double f = m.feed_for_force_mm(d, target);
      EXPECT_NEAR(m.force_n(d, f), target, 1e-9 * target) << d << " " << target;
    }
  }
  // The paper's power limit at 1500 rpm: F_ref = 745.7 W / V.
  const double v = 2 * M_PI * 0.025 * 1500 / 60;
  EXPECT_NEAR(m.feed_for_force_mm(1.0, 745.7 / v), 0.111, 0.001);
  EXPECT_TRUE(std::isnan(m.feed_for_force_mm(1.0, 0)));
  EXPECT_TRUE(std::isnan(m.feed_for_force_mm(0, 100)));
  mc::ForceProcessModel flat = m;
  flat.alpha = 0;
  EXPECT_TRUE(std::isnan(flat.feed_for_force_mm(1.0, 100)));
}

TEST(ForceProcess, FitRecoversTheModelFromExactSamples) {
  const mc::ForceProcessModel truth = mc::paper_force_process_model();
  std::vector<mc::ForceSample> samples;
  for (const double d : {0.5, 1.0, 1.5, 2.0}) {
    for (const double f : {0.05, 0.1, 0.2, 0.3}) samples.push_back({d, f, truth.force_n(d, f)});
  }
  const mc::ForceProcessModel fit = mc::fit_force_process(samples);
  EXPECT_NEAR(fit.k_kn, 0.76, 1e-10);
  EXPECT_NEAR(fit.beta, 0.65, 1e-10);
  EXPECT_NEAR(fit.alpha, 0.63, 1e-10);
  EXPECT_EQ(fit.provenance, mc::Provenance::fitted);
  ASSERT_TRUE(fit.fit.has_value());
  EXPECT_EQ(fit.fit->samples, 16u);
  EXPECT_NEAR(fit.fit->r_squared, 1.0, 1e-12);
  EXPECT_LT(fit.fit->rms_residual_n, 1e-8);
  EXPECT_LT(fit.fit->beta_stderr, 1e-8);
}

TEST(ForceProcess, FitStatisticsReflectTheNoise) {
  const mc::ForceProcessModel truth = mc::paper_force_process_model();
  std::vector<mc::ForceSample> samples;
  // Deterministic multiplicative "noise" of about 3 %.
  int i = 0;
  for (const double d : {0.5, 0.75, 1.0, 1.5, 2.0}) {
    for (const double f : {0.04, 0.07, 0.1, 0.15, 0.2, 0.3}) {
      const double noise = 0.03 * std::sin(12.9898 * ++i);
      samples.push_back({d, f, truth.force_n(d, f) * (1 + noise)});
    }
  }
  const mc::ForceProcessModel fit = mc::fit_force_process(samples);
  EXPECT_NEAR(fit.k_kn, 0.76, 0.04);
  EXPECT_NEAR(fit.beta, 0.65, 0.03);
  EXPECT_NEAR(fit.alpha, 0.63, 0.03);
  ASSERT_TRUE(fit.fit.has_value());
  EXPECT_GT(fit.fit->r_squared, 0.98);
  EXPECT_LT(fit.fit->r_squared, 1.0);
  EXPECT_GT(fit.fit->rms_residual_n, 1.0);
  EXPECT_LT(fit.fit->rms_residual_n, 15.0);
  // The true values lie within about three standard errors.
  EXPECT_LT(std::abs(fit.beta - 0.65), 4 * fit.fit->beta_stderr + 1e-3);
  EXPECT_LT(std::abs(fit.alpha - 0.63), 4 * fit.fit->alpha_stderr + 1e-3);
  EXPECT_GT(fit.fit->k_stderr, 0);
}

TEST(ForceProcess, FixedExponentAndBadSamples) {
  const mc::ForceProcessModel truth = mc::paper_force_process_model();
  // One depth only (what the edge sees during one pass): beta must be fixed.
  std::vector<mc::ForceSample> one_depth;
  for (const double f : {0.05, 0.1, 0.2}) one_depth.push_back({1.0, f, truth.force_n(1.0, f)});
  EXPECT_THROW(mc::fit_force_process(one_depth), std::invalid_argument);
  mc::FitOptions o;
  o.fixed_beta = 0.65;
  const mc::ForceProcessModel fit = mc::fit_force_process(one_depth, o);
  EXPECT_NEAR(fit.k_kn, 0.76, 1e-10);
  EXPECT_NEAR(fit.alpha, 0.63, 1e-10);
  EXPECT_DOUBLE_EQ(fit.beta, 0.65);
  EXPECT_EQ(fit.fit->beta_stderr, 0);

  std::vector<mc::ForceSample> bad = one_depth;
  bad[1].force_n = -2;
  try {
    mc::fit_force_process(bad, o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "samples[1].force_n: must be > 0, got -2");
  }
  EXPECT_THROW(mc::fit_force_process(std::vector<mc::ForceSample>{}), std::invalid_argument);
}
