// The detector study's own counting of the label's rule on q read with an
// error: with none it is the label; near the threshold an error of a few
// per cent makes the label's own failures; far from it, none.

#include "label_rule.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace {

using smc::bench::LabelledCut;
using smc::bench::Outcome;

// A cut of comparable revolutions 0.1 s long with these q, labelled as the
// label's own rule labels it (the onset: the first sample of the onset
// revolution; -1: stable).
LabelledCut cut_of(const std::vector<double>& q) {
  LabelledCut cut;
  cut.rpm = 600;  // a revolution every 0.1 s
  for (size_t r = 0; r < q.size(); ++r) {
    smc::edge::RevolutionChange c;
    c.first_sample = r * 10;
    c.end_sample = (r + 1) * 10;
    c.q = q[r];
    c.comparable = true;
    cut.changes.push_back(c);
    cut.end_s.push_back(0.1 * static_cast<double>(r + 1));
  }
  smc::edge::mark_onsets(cut.changes);
  for (size_t r = 0; r < cut.changes.size(); ++r) {
    if (cut.changes[r].onset()) {
      cut.onset_s = 0.1 * static_cast<double>(r);
      break;
    }
  }
  return cut;
}

// How many of `draws` readings of `cut` with a relative error `sigma`
// the label's rule decides as `outcome`.
int times(const LabelledCut& cut, double sigma, Outcome outcome, int draws = 100) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> error(0.0, sigma);
  std::vector<smc::edge::RevolutionChange> read;
  int n = 0;
  for (int d = 0; d < draws; ++d)
    n += smc::bench::label_rule_outcome(cut, rng, error, read) == outcome;
  return n;
}

const std::vector<double> kFarBelow = {0.02, 0.03, 0.05, 0.08, 0.10, 0.09, 0.06, 0.04, 0.03, 0.02};
const std::vector<double> kJustBelow = {0.02,   0.03, 0.05, 0.10, 0.1496,
                                        0.1498, 0.10, 0.05, 0.03, 0.02};
const std::vector<double> kGrowing = {0.02, 0.03, 0.05, 0.10, 0.20, 0.30, 0.45, 0.60, 0.80, 0.90};
const std::vector<double> kJustAbove = {0.02,   0.03, 0.05, 0.10, 0.1504,
                                        0.1506, 0.10, 0.05, 0.03, 0.02};

TEST(LabelRuleOnError, WithoutAnErrorItIsTheLabel) {
  for (const auto& q : {kFarBelow, kJustBelow}) {
    const LabelledCut stable = cut_of(q);
    ASSERT_LT(stable.onset_s, 0);
    EXPECT_EQ(times(stable, 0.0, Outcome::kQuiet), 100);
  }
  for (const auto& q : {kGrowing, kJustAbove}) {
    const LabelledCut unstable = cut_of(q);
    ASSERT_GE(unstable.onset_s, 0);
    EXPECT_EQ(times(unstable, 0.0, Outcome::kWithin3), 100);
  }
}

TEST(LabelRuleOnError, NearTheThresholdAnErrorOfTwoPerCentMakesTheLabelsOwnFailures) {
  // A stable cut 0.3 % below the threshold reads as chatter; an unstable
  // one 0.3 % above it as stable (its onset missed).
  EXPECT_GE(times(cut_of(kJustBelow), 0.02, Outcome::kFalse), 5);
  EXPECT_GE(times(cut_of(kJustAbove), 0.02, Outcome::kMissed), 5);
  // Far from it, never.
  EXPECT_EQ(times(cut_of(kFarBelow), 0.02, Outcome::kFalse), 0);
  EXPECT_EQ(times(cut_of(kGrowing), 0.02, Outcome::kWithin3), 100);
}

TEST(LabelRuleOnError, AFailureIsTheSameKindAsAnother) {
  using smc::bench::same_failure;
  EXPECT_TRUE(same_failure(Outcome::kFalse, Outcome::kFalse));
  EXPECT_TRUE(same_failure(Outcome::kLate, Outcome::kMissed));
  EXPECT_TRUE(same_failure(Outcome::kMissed, Outcome::kLate));
  EXPECT_FALSE(same_failure(Outcome::kFalse, Outcome::kLate));
  EXPECT_FALSE(same_failure(Outcome::kLate, Outcome::kFalse));
  EXPECT_FALSE(same_failure(Outcome::kLate, Outcome::kWithin3));
  EXPECT_FALSE(same_failure(Outcome::kFalse, Outcome::kQuiet));
  EXPECT_FALSE(same_failure(Outcome::kQuiet, Outcome::kQuiet));
}

}  // namespace
