// Evolution rules (IEC 60848) on small Grafcets written for each rule.

#include "smc/grafcet/engine.hpp"

#include <gtest/gtest.h>

#include "grafcet_test_util.hpp"

namespace smc::grafcet {
namespace {

using testing::inputs;
using testing::parse_ok;
using testing::step_numbers;

TEST(GrafcetEngine, AllFirableTransitionsFireTogetherAndSynchronise) {
  // 1 -> (a) -> 2 and 3 in parallel; 2 -> (b) -> 4; 3 -> (c) -> 5; 4 and 5 -> (1) -> 6.
  const Grafcet g = parse_ok(
      "input a, b, c\nstep 1 initial\nstep 2\nstep 3\nstep 4\nstep 5\nstep 6\n"
      "transition 1: 1 -> 2, 3 when a\n"
      "transition 2: 2 -> 4 when b\n"
      "transition 3: 3 -> 5 when c\n"
      "transition 4: 4, 5 -> 6 when 1\n"
      "transition 5: 6 -> 1 when a'\n");
  Engine e(g);
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "1");
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "2 3");
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a b")).active_steps), "3 4");
  // (4) is enabled only when both 4 and 5 are active.
  const Evaluation& r = e.evaluate(inputs(g, "a b c"));
  EXPECT_EQ(step_numbers(g, r.active_steps), "6");
  EXPECT_EQ(r.rounds, 2u);  // (3), then (4) in a transient round
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "1");
  // b and c together from {2, 3}: (2) and (3) fire in the same round.
  e.evaluate(inputs(g, "a"));
  const Evaluation& both = e.evaluate(inputs(g, "a b c"));
  EXPECT_EQ(step_numbers(g, both.active_steps), "6");
  EXPECT_EQ(both.rounds, 2u);
}

TEST(GrafcetEngine, ActivationWinsOverDeactivation) {
  // 2 is deactivated by (2) and activated by (1) in the same round: it stays.
  // (Edges, so that no second round fires (2) again.)
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2 initial\nstep 3\n"
      "transition 1: 1 -> 2 when ↑a\ntransition 2: 2 -> 3 when ↑a\n"
      "transition 3: 3 -> 1 when 0\n");
  Engine e(g);
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "1 2");
  const Evaluation& r = e.evaluate(inputs(g, "a"));
  EXPECT_EQ(step_numbers(g, r.active_steps), "2 3");
}

TEST(GrafcetEngine, TransientStepsFireImpulsesButNotLevelActions) {
  const Grafcet g = parse_ok(
      "input a, b\nstep 1 initial: P*\nstep 2: L2, I2*\nstep 3: L3, I3*\nstep 4: L4\n"
      "transition 1: 1 -> 2 when a\ntransition 2: 2 -> 3 when 1\n"
      "transition 3: 3 -> 4 when b\ntransition 4: 4 -> 1 when a' b'\n");
  Engine e(g);
  const Evaluation& first = e.evaluate(inputs(g, "b"));
  EXPECT_EQ(step_numbers(g, first.active_steps), "1");
  EXPECT_EQ(testing::action_names(g, first.impulse_actions), "P");  // initial step, once
  EXPECT_TRUE(first.changed);
  const Evaluation& r = e.evaluate(inputs(g, "a b"));
  EXPECT_EQ(step_numbers(g, r.active_steps), "4");
  EXPECT_EQ(r.rounds, 3u);
  EXPECT_EQ(testing::action_names(g, r.level_actions), "L4");
  EXPECT_EQ(testing::action_names(g, r.impulse_actions), "I2I3");
  EXPECT_EQ(step_numbers(g, r.activated_steps), "2 3 4");
  EXPECT_TRUE(r.changed);
  const Evaluation& again = e.evaluate(inputs(g, "a b"));
  EXPECT_FALSE(again.changed);
  EXPECT_EQ(again.impulse_actions, 0u);
  EXPECT_EQ(again.rounds, 0u);
  // Stopping in step 3 (b false): its level action shows.
  e.evaluate(0);
  const Evaluation& three = e.evaluate(inputs(g, "a"));
  EXPECT_EQ(step_numbers(g, three.active_steps), "3");
  EXPECT_EQ(testing::action_names(g, three.level_actions), "L3");
}

TEST(GrafcetEngine, EdgesAreSeenByTheFirstRoundOnly) {
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2\nstep 3\nstep 4\n"
      "transition 1: 1 -> 2 when ↑a\ntransition 2: 2 -> 3 when ↑a\n"
      "transition 3: 3 -> 4 when ↓a\ntransition 4: 4 -> 1 when 1\n");
  Engine e(g);
  // The first evaluation after reset sees no edge even though a = 1.
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "1");
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "1");
  // One rising edge: (1) fires, (2) is enabled only after it and does not.
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "2");
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "2");  // level: no edge
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "2");
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "3");
  // Falling edge: 3 -> 4 then 4 -> 1 in a transient round.
  const Evaluation& r = e.evaluate(0);
  EXPECT_EQ(step_numbers(g, r.active_steps), "1");
  EXPECT_EQ(step_numbers(g, r.activated_steps), "1 4");
}

TEST(GrafcetEngine, UnstableCycleIsReportedNotLooped) {
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2\n"
      "transition 1: 1 -> 2 when a\ntransition 2: 2 -> 1 when a\n");
  Engine e(g, EngineOptions{.max_rounds = 7});
  EXPECT_FALSE(e.evaluate(0).unstable);
  const Evaluation& r = e.evaluate(inputs(g, "a"));
  EXPECT_TRUE(r.unstable);
  EXPECT_EQ(r.rounds, 7u);
  EXPECT_EQ(step_numbers(g, r.active_steps), "2");  // 7 rounds from 1: stopped in 2
  const Evaluation& calm = e.evaluate(0);
  EXPECT_FALSE(calm.unstable);
  EXPECT_EQ(step_numbers(g, calm.active_steps), "2");
}

TEST(GrafcetEngine, SelfLoopIsStableAndDoesNotRefireImpulses) {
  const Grafcet g = parse_ok("input a\nstep 1 initial: P*, L\ntransition 1: 1 -> 1 when a\n");
  Engine e(g);
  EXPECT_EQ(e.evaluate(0).impulse_actions, 1u);
  const Evaluation& r = e.evaluate(inputs(g, "a"));
  EXPECT_FALSE(r.unstable);
  EXPECT_FALSE(r.changed);
  EXPECT_EQ(r.impulse_actions, 0u);
  EXPECT_EQ(step_numbers(g, r.active_steps), "1");
}

TEST(GrafcetEngine, CheckingOrderLetsOnlyTheFirstFirableFire) {
  // Declared order (3) before (2) although (2) is declared first.
  const Grafcet g = parse_ok(
      "input a, b\nstep 1 initial\nstep 2\nstep 3\n"
      "transition 2: 1 -> 2 when a\ntransition 3: 1 -> 3 when b\n"
      "transition 4: 2 -> 1 when 0\ntransition 5: 3 -> 1 when 0\n"
      "order 1: 3, 2\n");
  Engine e(g);
  e.evaluate(0);
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a b")).active_steps), "3");
  e.reset();
  e.evaluate(0);
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a")).active_steps), "2");
}

TEST(GrafcetEngine, WithoutOrderConflictingTransitionsBothFire) {
  const Grafcet g = parse_ok(
      "input a, b\nstep 1 initial\nstep 2\nstep 3\n"
      "transition 2: 1 -> 2 when a\ntransition 3: 1 -> 3 when b\n"
      "transition 4: 2 -> 1 when 0\ntransition 5: 3 -> 1 when 0\n");
  Engine e(g);
  e.evaluate(0);
  EXPECT_EQ(step_numbers(g, e.evaluate(inputs(g, "a b")).active_steps), "2 3");
}

TEST(GrafcetEngine, ReceptivitiesReadStepVariables) {
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2\nstep 10 initial\nstep 11\n"
      "transition 1: 1 -> 2 when a\ntransition 2: 2 -> 1 when a'\n"
      "transition 3: 10 -> 11 when X2\ntransition 4: 11 -> 10 when X1\n");
  Engine e(g);
  EXPECT_EQ(step_numbers(g, e.evaluate(0).active_steps), "1 10");
  // 1 -> 2 in round 1, then 10 -> 11 in round 2 (X2 now true).
  const Evaluation& r = e.evaluate(inputs(g, "a"));
  EXPECT_EQ(step_numbers(g, r.active_steps), "2 11");
  EXPECT_EQ(r.rounds, 2u);
}

TEST(GrafcetEngine, ResetReturnsToTheInitialSituationAndRefiresItsImpulses) {
  const Grafcet g = testing::load_ok("smc1.grafcet");
  Engine e(g);
  const int L = e.action_index("L");
  ASSERT_GE(L, 0);
  EXPECT_EQ(step_numbers(g, e.last().active_steps), "1");
  EXPECT_EQ(e.last().impulse_actions, 0u);
  EXPECT_EQ(e.evaluate(0).impulse_actions, Mask{1} << L);
  e.evaluate(inputs(g, "b"));
  EXPECT_EQ(step_numbers(g, e.last().active_steps), "4");
  e.reset();
  EXPECT_EQ(step_numbers(g, e.last().active_steps), "1");
  const Evaluation& r = e.evaluate(0);
  EXPECT_EQ(r.impulse_actions, Mask{1} << L);
  EXPECT_TRUE(r.changed);
  EXPECT_EQ(step_numbers(g, r.active_steps), "2");
}

TEST(GrafcetEngine, NamesAndIndices) {
  const Grafcet g = testing::load_ok("smc2.grafcet");
  const Engine e(g);
  EXPECT_EQ(e.num_inputs(), 5u);
  EXPECT_EQ(e.num_steps(), 6u);
  EXPECT_EQ(e.num_actions(), g.actions().size());
  EXPECT_EQ(e.input_index("a"), 0);
  EXPECT_EQ(e.input_index("d"), 3);
  EXPECT_EQ(e.input_index("zz"), -1);
  EXPECT_EQ(e.step_index(6), 5);
  EXPECT_EQ(e.step_index(7), -1);
  EXPECT_EQ(e.step_number(3), 4u);
  EXPECT_EQ(e.step_number(99), 0u);
  EXPECT_EQ(e.input_name(4), "e");
  EXPECT_EQ(e.action_name(static_cast<std::size_t>(e.action_index("G"))), "G");
  EXPECT_EQ(e.action_index("L"), -1);  // not in SMC II
  EXPECT_EQ(e.initial_steps(), Mask{1});
}

TEST(GrafcetEngine, UndeclaredInputBitsAreIgnored) {
  const Grafcet g = testing::load_ok("smc1.grafcet");
  Engine e(g);
  e.evaluate(~Mask{0} << 5);  // only bits beyond a..e
  EXPECT_EQ(step_numbers(g, e.evaluate(~Mask{0} << 5).active_steps), "2");
}

TEST(GrafcetEngine, MovedEngineKeepsItsSituation) {
  const Grafcet g = testing::load_ok("smc1.grafcet");
  Engine a(g);
  a.evaluate(inputs(g, "b"));
  Engine b(std::move(a));
  EXPECT_EQ(step_numbers(g, b.last().active_steps), "4");
  EXPECT_EQ(step_numbers(g, b.evaluate(0).active_steps), "2");
}

}  // namespace
}  // namespace smc::grafcet
