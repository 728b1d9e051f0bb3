// The verifier passes the shipped supervisors (the paper's two and the
// guarded SMC I) and catches every seeded defect, with a shortest input
// sequence that the Engine replays to the same situation.

#include "smc/grafcet/verifier.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "grafcet_test_util.hpp"

namespace smc::grafcet {
namespace {

using testing::load_ok;
using testing::parse_ok;

std::set<Check> checks_of(const Report& r) {
  std::set<Check> s;
  for (const Violation& v : r.violations) s.insert(v.check);
  return s;
}

// Replays a counterexample path through a fresh Engine: every evaluation
// must reach the situation the verifier recorded. Returns the last result.
Evaluation replay(const Grafcet& g, const std::vector<PathStep>& path) {
  Engine e(g);
  Evaluation last = e.last();
  for (std::size_t k = 0; k < path.size(); ++k) {
    last = e.evaluate(path[k].inputs);
    if (path[k].stable) {
      EXPECT_FALSE(last.unstable) << "evaluation " << k + 1;
      EXPECT_EQ(last.active_steps, path[k].steps) << "evaluation " << k + 1;
      EXPECT_EQ(last.impulse_actions, path[k].impulses) << "evaluation " << k + 1;
    }
  }
  return last;
}

TEST(GrafcetVerifier, PaperSupervisorsPass) {
  for (const char* file : {"smc1.grafcet", "smc1_guarded.grafcet", "smc2.grafcet"}) {
    const Grafcet g = load_ok(file);
    const Report r = verify(g);
    EXPECT_TRUE(r.ok()) << format_report(g, r);
    EXPECT_EQ(r.reachable_steps, (Mask{1} << g.steps().size()) - 1) << file;
    // Steps 1 and 3 are transient: the stable situations are X2, X4, X5 (and X6).
    EXPECT_EQ(r.stable_situations, g.steps().size() - 2) << file;
    EXPECT_EQ(r.invariants.size(), g.invariants().size());
    for (const InvariantResult& inv : r.invariants) {
      EXPECT_TRUE(inv.held) << file << ": " << inv.name;
      EXPECT_EQ(inv.evaluations, r.evolutions) << file << ": " << inv.name;
    }
    EXPECT_LE(r.longest_transient, 3u);  // e.g. 5 -> 2 -> 3 -> 4
    EXPECT_GE(r.longest_transient, 2u);
    const std::string text = format_report(g, r);
    EXPECT_NE(text.find("PASS: no violation"), std::string::npos) << text;
  }
}

std::string read_text(const std::string& file) {
  std::ostringstream buffer;
  buffer << std::ifstream(testing::grafcet_path(file)).rdbuf();
  return buffer.str();
}

// The statements of a Grafcet text: comments and blank lines dropped.
std::vector<std::string> statements(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    out.push_back(line);
  }
  return out;
}

// A mutated copy of the guarded SMC I: L left active in the suppression
// step. Refused on the two invariants that say so, with the path contact ->
// chatter detected, which the engine replays to X6 with L and G active.
TEST(GrafcetVerifier, GuardedSmcOneWithLDuringTheRoutineIsRefused) {
  const std::string file = "broken/smc1_guarded_l_in_routine.grafcet";
  // The copy differs from the shipped supervisor in its name and step 6 only.
  const auto shipped = statements(read_text("smc1_guarded.grafcet"));
  const auto broken = statements(read_text(file));
  ASSERT_EQ(shipped.size(), broken.size());
  std::vector<std::string> differ;
  for (std::size_t i = 0; i < shipped.size(); ++i) {
    if (shipped[i] != broken[i]) differ.push_back(broken[i]);
  }
  ASSERT_EQ(differ.size(), 2u);
  EXPECT_EQ(differ[0].rfind("grafcet broken_smc1_guarded ", 0), 0u) << differ[0];
  EXPECT_EQ(differ[1], "step 6 \"chatter suppression routine\":    A, G, L");

  const Grafcet g = load_ok(file);
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kInvariant}) << format_report(g, r);
  std::set<std::string> violated;
  for (const Violation& v : r.violations) violated.insert(v.subject);
  EXPECT_EQ(violated, (std::set<std::string>{
                          "invariant \"L while in contact (step 4)\"",
                          "invariant \"force controller never during the routine's hold\""}));
  const Violation& v = r.violations[0];
  ASSERT_EQ(v.path.size(), 2u);
  EXPECT_EQ(v.path[0].inputs, testing::inputs(g, "b"));
  EXPECT_EQ(v.path[1].inputs, testing::inputs(g, "b d"));
  const Evaluation last = replay(g, v.path);
  const Mask l = Mask{1} << g.action_index("L");
  const Mask gg = Mask{1} << g.action_index("G");
  EXPECT_EQ(last.level_actions & (l | gg), l | gg);
  EXPECT_NE(format_report(g, r).find("FAIL: 2 violations"), std::string::npos);
}

// SMC II+ (beyond the paper): every step reachable, every invariant held --
// among them no feed while a breakage is latched and at most one speed
// change per pass. Steps 1, 3 and 8 are transient.
TEST(GrafcetVerifier, SmcTwoPlusPasses) {
  const Grafcet g = load_ok("smc2_plus.grafcet");
  const Report r = verify(g);
  EXPECT_TRUE(r.ok()) << format_report(g, r);
  EXPECT_EQ(r.reachable_steps, (Mask{1} << g.steps().size()) - 1);
  EXPECT_EQ(r.stable_situations, g.steps().size() - 3);
  EXPECT_EQ(r.invariants.size(), g.invariants().size());
  std::set<std::string> names;
  for (const InvariantResult& inv : r.invariants) {
    EXPECT_TRUE(inv.held) << inv.name;
    EXPECT_EQ(inv.evaluations, r.evolutions) << inv.name;
    names.insert(inv.name);
  }
  EXPECT_TRUE(names.count("no feed while a breakage is latched"));
  EXPECT_TRUE(names.count("at most one speed change per pass"));
}

// A mutated SMC II+ that changes speed for every chatter is refused, with
// the path: contact, then chatter in a pass that already had its change.
TEST(GrafcetVerifier, SmcTwoPlusWithASecondSpeedChangeIsRefused) {
  const std::string file = "broken/smc2_plus_second_speed_change.grafcet";
  const auto shipped = statements(read_text("smc2_plus.grafcet"));
  const auto broken = statements(read_text(file));
  ASSERT_EQ(shipped.size(), broken.size());
  std::vector<std::string> differ;
  for (std::size_t i = 0; i < shipped.size(); ++i) {
    if (shipped[i] != broken[i]) differ.push_back(broken[i]);
  }
  ASSERT_EQ(differ.size(), 3u);
  EXPECT_EQ(differ[1], "transition 10: 4 -> 7 when ↑d");
  EXPECT_EQ(differ[2], "order 4: 5, 13, 7, 10, 6");
  const Grafcet g = load_ok(file);
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kInvariant}) << format_report(g, r);
  std::set<std::string> violated;
  for (const Violation& v : r.violations) violated.insert(v.subject);
  EXPECT_TRUE(violated.count("invariant \"at most one speed change per pass\""))
      << format_report(g, r);
  for (const Violation& v : r.violations) {
    if (v.subject != "invariant \"at most one speed change per pass\"") continue;
    ASSERT_EQ(v.path.size(), 2u);
    EXPECT_EQ(v.path[1].inputs, testing::inputs(g, "b d h"));
    const Evaluation last = replay(g, v.path);
    EXPECT_EQ(last.level_actions & (Mask{1} << g.action_index("O")),
              Mask{1} << g.action_index("O"));
  }
}

TEST(GrafcetVerifier, SeededConflict) {
  const Grafcet g = load_ok("broken/conflict.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kConflict}) << format_report(g, r);
  ASSERT_EQ(r.violations.size(), 1u);
  const Violation& v = r.violations[0];
  EXPECT_NE(v.subject.find("step 2"), std::string::npos) << v.subject;
  EXPECT_NE(v.subject.find("(2) and (3)"), std::string::npos) << v.subject;
  // Shortest: feed hold and contact together in the very first evaluation.
  ASSERT_EQ(v.path.size(), 1u);
  EXPECT_EQ(v.path[0].inputs, testing::inputs(g, "a b"));
  replay(g, v.path);
}

TEST(GrafcetVerifier, SeededUnreachableStep) {
  const Grafcet g = load_ok("broken/unreachable.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kUnreachableStep}) << format_report(g, r);
  ASSERT_EQ(r.violations.size(), 1u);
  EXPECT_EQ(r.violations[0].subject, "step 6");
  EXPECT_EQ(r.violations[0].where.line, 14u);
  EXPECT_TRUE(r.violations[0].path.empty());
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_EQ(r.notes[0], "transition (9) never fires");
}

TEST(GrafcetVerifier, SeededDeadlock) {
  const Grafcet g = load_ok("broken/deadlock.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kDeadlock}) << format_report(g, r);
  ASSERT_EQ(r.violations.size(), 1u);
  const Violation& v = r.violations[0];
  EXPECT_EQ(v.subject, "situation X6");
  // Contact, then chatter: two evaluations.
  ASSERT_EQ(v.path.size(), 2u);
  replay(g, v.path);
  EXPECT_EQ(v.path.back().steps, Mask{1} << 5);
  // Indeed no valuation leaves X6 (nor from any previous inputs).
  for (Mask previous = 0; previous < 16; ++previous)
    for (Mask in = 0; in < 16; ++in) {
      std::vector<PathStep> p = v.path;
      p.push_back({previous, 0, 0, false});
      p.push_back({in, 0, 0, false});
      EXPECT_EQ(replay(g, p).active_steps, Mask{1} << 5);
    }
}

TEST(GrafcetVerifier, SeededTransientCycle) {
  const Grafcet g = load_ok("broken/transient_cycle.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kTransientCycle}) << format_report(g, r);
  const Violation& v = r.violations[0];
  EXPECT_NE(v.subject.find("X2 -> X3 -> X4 -> X2"), std::string::npos) << v.subject;
  ASSERT_FALSE(v.path.empty());
  EXPECT_FALSE(v.path.back().stable);
  EXPECT_TRUE(replay(g, v.path).unstable);
}

TEST(GrafcetVerifier, PrintedSmc2HasATransientCycle) {
  const Grafcet g = load_ok("broken/smc2_printed.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kTransientCycle}) << format_report(g, r);
  EXPECT_TRUE(replay(g, r.violations[0].path).unstable);
}

TEST(GrafcetVerifier, SeededInvariantViolation) {
  const Grafcet g = load_ok("broken/invariant.grafcet");
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kInvariant}) << format_report(g, r);
  ASSERT_EQ(r.violations.size(), 1u);
  const Violation& v = r.violations[0];
  EXPECT_EQ(v.subject, "invariant \"force controller never during feed hold\"");
  ASSERT_EQ(r.invariants.size(), 2u);
  EXPECT_TRUE(r.invariants[0].held);
  EXPECT_FALSE(r.invariants[1].held);
  // Shortest: a feed hold at the first evaluation.
  ASSERT_EQ(v.path.size(), 1u);
  const Evaluation last = replay(g, v.path);
  const Mask k = Mask{1} << g.action_index("K");
  const Mask c = Mask{1} << g.action_index("C");
  EXPECT_EQ(last.level_actions & (k | c), k | c);
  const std::string text = format_report(g, r);
  EXPECT_NE(text.find("1. a=1 b=0 c=0 d=0 e=0  ->  X5"), std::string::npos) << text;
  EXPECT_NE(text.find("FAIL: 1 violation"), std::string::npos) << text;
}

TEST(GrafcetVerifier, NextStableSituationInvariant) {
  // "Whenever a is true, the next stable situation has step 5 active": true
  // for SMC I; false for SMC II, whose step 6 ignores the feed hold.
  const std::string invariant = "\ninvariant \"feed hold\": a -> next X5\n";
  for (const char* file : {"smc1.grafcet", "smc2.grafcet"}) {
    ParseResult p = parse_file(testing::grafcet_path(file));
    ASSERT_TRUE(p.ok());
    std::ostringstream buffer;
    buffer << std::ifstream(testing::grafcet_path(file)).rdbuf();
    const std::string text = buffer.str();
    const Grafcet g = parse_ok(text + invariant);
    const Report r = verify(g);
    if (std::string(file) == "smc1.grafcet") {
      EXPECT_TRUE(r.ok()) << format_report(g, r);
      continue;
    }
    ASSERT_EQ(checks_of(r), std::set<Check>{Check::kInvariant}) << format_report(g, r);
    const Violation& v = r.violations[0];
    // Contact, chatter, then a: the shortest way to have a in step 6.
    ASSERT_EQ(v.path.size(), 3u);
    EXPECT_EQ(v.path[1].steps, Mask{1} << 5);
    EXPECT_NE(v.path[2].inputs & testing::inputs(g, "a"), 0u);
    EXPECT_EQ(replay(g, v.path).active_steps, Mask{1} << 5);
  }
}

TEST(GrafcetVerifier, TransientLongerThanTheEngineBound) {
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2\nstep 3\nstep 4\nstep 5\n"
      "transition 1: 1 -> 2 when a\ntransition 2: 2 -> 3 when 1\n"
      "transition 3: 3 -> 4 when 1\ntransition 4: 4 -> 5 when 1\n"
      "transition 5: 5 -> 1 when a'\n");
  EXPECT_TRUE(verify(g, {.max_rounds = 4}).ok());
  const Report r = verify(g, {.max_rounds = 3});
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kRoundBound}) << format_report(g, r);
  // The engine with that bound indeed stops early and says so.
  Engine e(g, {.max_rounds = 3});
  e.evaluate(0);
  EXPECT_TRUE(e.evaluate(1).unstable);
}

TEST(GrafcetVerifier, TooManyInputsForExhaustiveExploration) {
  std::string text = "step 1 initial\nstep 2\n";
  std::string sum;
  for (int i = 0; i < 21; ++i) {
    text += "input i" + std::to_string(i) + "\n";
    sum += (i ? " + i" : "i") + std::to_string(i);
  }
  text += "transition 1: 1 -> 2 when " + sum + "\ntransition 2: 2 -> 1 when 1\n";
  const Grafcet g = parse_ok(text);
  const Report r = verify(g);
  ASSERT_EQ(checks_of(r), std::set<Check>{Check::kLimit});
  EXPECT_EQ(r.evolutions, 0u);
}

TEST(GrafcetVerifier, EdgeInputsArePartOfTheState) {
  // ↑a needs a to fall and rise again: no deadlock although a = 1 alone
  // cannot leave step 2 twice in a row.
  const Grafcet g = parse_ok(
      "input a\nstep 1 initial\nstep 2\nstep 3\n"
      "transition 1: 1 -> 2 when 1\ntransition 2: 2 -> 3 when ↑a\n"
      "transition 3: 3 -> 2 when ↑a\n"
      "invariant \"edge\": X2 ↑a -> next X3\n");
  const Report r = verify(g);
  EXPECT_TRUE(r.ok()) << format_report(g, r);
  EXPECT_EQ(r.states, 5u);  // root, then X2 and X3 each with a = 0 or 1
}

}  // namespace
}  // namespace smc::grafcet
