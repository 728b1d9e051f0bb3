// The cell's learning policy (smc/cell/learning.hpp): stability bounds from
// a part's evidence, a milling model checked against them, a force model's
// prediction error and the count of checks passed in a row.
#include "smc/cell/learning.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "smc/documents/load.hpp"

namespace {

using smc::cell::BoundCheck;
using smc::cell::StabilityBound;
namespace store = smc::cell::store;

store::StabilityEvidence point(const char* machine, double rpm, double depth, bool chatter,
                               double feed = 0.09, const char* job = "j1") {
  store::StabilityEvidence e;
  e.machine_id = machine;
  e.tool_id = "t";
  e.job_id = job;
  e.spindle_rpm = rpm;
  e.depth_mm = depth;
  e.feed_per_tooth_mm = feed;
  e.chatter = chatter;
  e.revolutions = chatter ? 0 : 100;
  return e;
}

TEST(Learning, BoundsKeepTheDeepestCleanCutAndTheShallowestChatterPerMachineAndSpeed) {
  const auto b = smc::cell::stability_bounds(
      {point("m1", 1500, 1.0, false), point("m1", 1500.4, 1.2, false, 0.07, "j2"),
       point("m1", 1500, 2.0, true, 0.05), point("m1", 1500, 1.8, true, 0.04, "j3"),
       point("m2", 1500, 0.5, false), point("m1", 1100, 1.0, true)});
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].rpm, 1100);
  EXPECT_FALSE(b[0].stable_mm > 0);
  EXPECT_DOUBLE_EQ(b[0].chatter_mm, 1.0);
  const auto& m1 = b[1];
  EXPECT_EQ(m1.machine_id, "m1");
  EXPECT_EQ(m1.rpm, 1500);
  EXPECT_DOUBLE_EQ(m1.stable_mm, 1.2);
  EXPECT_DOUBLE_EQ(m1.stable_feed_mm, 0.07);
  EXPECT_EQ(m1.revolutions, 200u);
  EXPECT_DOUBLE_EQ(m1.chatter_mm, 1.8);
  EXPECT_DOUBLE_EQ(m1.chatter_feed_mm, 0.04);
  EXPECT_EQ(m1.jobs.size(), 3u);
  EXPECT_FALSE(m1.disagrees());
  EXPECT_EQ(b[2].machine_id, "m2");
  EXPECT_FALSE(b[2].has_chatter());
  // A clean cut deeper than a chatter: the bound disagrees with itself.
  EXPECT_TRUE(
      smc::cell::stability_bounds({point("m1", 1500, 2.0, false), point("m1", 1500, 1.5, true)})[0]
          .disagrees());
}

smc::config::MillingModel paper_mill() {
  smc::config::MillingModel m;
  smc::documents::load(std::string(SMC_SOURCE_DIR) + "/cell/models/paper_face_mill.textproto", m);
  return m;
}

// The paper's mill at 1500 rpm: critical depth about 1.8 mm at the
// controller's feed (cell/README.md).
TEST(Learning, AMillingModelIsCheckedAgainstTheLimitThePartsCutsBound) {
  StabilityBound b;
  b.rpm = 1500;
  b.stable_mm = 1.0;
  b.stable_feed_mm = 0.09;
  b.chatter_mm = 2.0;
  b.chatter_feed_mm = 0.09;
  const auto ok = smc::cell::check_against(paper_mill(), b);
  EXPECT_TRUE(ok.brackets());
  EXPECT_GT(ok.critical_at_stable_mm, 1.0);
  EXPECT_LT(ok.critical_at_chatter_mm, 2.0);
  // Chatter at 1.2 mm: below the model's limit, so the model is wrong.
  b.chatter_mm = 1.2;
  const auto low = smc::cell::check_against(paper_mill(), b);
  EXPECT_TRUE(low.contradicted_by_chatter);
  EXPECT_FALSE(low.brackets());
  // A clean cut at 1.95 mm: above the model's limit.
  b.chatter_mm = 0;
  b.stable_mm = 1.95;
  const auto high = smc::cell::check_against(paper_mill(), b);
  EXPECT_TRUE(high.contradicted_by_stable);
  EXPECT_EQ(high.critical_at_chatter_mm, -1);
  EXPECT_FALSE(high.brackets()) << "one end only: consistent, but not bracketed";
}

TEST(Learning, PredictionErrorIsTheMeanRelativeErrorOfFy) {
  smc::machining::ForceProcessModel m;
  m.k_kn = 0.76;
  m.beta = 0.65;
  m.alpha = 0.63;
  const double exact = m.force_n(1.0, 0.09);
  const std::vector<smc::machining::ForceSample> s{
      {1.0, 0.09, exact}, {1.0, 0.09, exact / 1.1}, {1.0, 0.09, -1}};  // the last one ignored
  EXPECT_NEAR(smc::cell::mean_abs_error_pct(m, s), 5.0, 1e-9);
  EXPECT_TRUE(std::isnan(smc::cell::mean_abs_error_pct(m, {})));
}

TEST(Learning, ChecksPassedInARowRestartAfterAFailureASuspicionOrAValidation) {
  auto ev = [](const char* action, const char* detail = "") {
    store::CatalogEvent e;
    e.action = action;
    e.detail = detail;
    return e;
  };
  EXPECT_EQ(smc::cell::passed_in_a_row({}), 0);
  EXPECT_EQ(
      smc::cell::passed_in_a_row({ev("created"), ev("checked", "passed"), ev("checked", "passed")}),
      2);
  EXPECT_EQ(smc::cell::passed_in_a_row(
                {ev("checked", "passed"), ev("checked", "failed"), ev("checked", "passed")}),
            1);
  EXPECT_EQ(smc::cell::passed_in_a_row({ev("checked", "passed"), ev("suspected")}), 0);
  EXPECT_EQ(smc::cell::passed_in_a_row({ev("checked", "passed"), ev("validated")}), 0);
}

}  // namespace
