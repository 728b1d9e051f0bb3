// The paper's two supervisors driven by scripted input sequences through
// every sequence of situations the text describes. At every evaluation: one
// active step, the expected one; the active modules are those the rules of
// shared/DOMAIN.md give for that step; the impulse actions are the expected
// initialisations/resets.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>

#include "grafcet_test_util.hpp"
#include "smc/grafcet/engine.hpp"

namespace smc::grafcet {
namespace {

// SMC I rules: A and B always; I and J unless step 5; L while in contact
// (step 4); C, the feed hold, in step 5.
std::string smc1_modules(std::uint32_t step) {
  std::string m = "AB";
  if (step != 5) m += "IJ";
  if (step == 4) m += "L";
  if (step == 5) m += "C";
  std::sort(m.begin(), m.end());
  return m;
}

// SMC II rules: A always; B unless step 6; I and J unless step 5 or 6;
// D, E, H, K while in contact (step 4); G on chatter (step 6); C in step 5.
std::string smc2_modules(std::uint32_t step) {
  std::string m = "A";
  if (step != 6) m += "B";
  if (step != 5 && step != 6) m += "IJ";
  if (step == 4) m += "DEHK";
  if (step == 6) m += "G";
  if (step == 5) m += "C";
  std::sort(m.begin(), m.end());
  return m;
}

// Guarded SMC I rules (cell/grafcets/smc1_guarded.grafcet): SMC I's, with E
// beside L while in contact (step 4) and SMC II's suppression routine: B
// unless step 6, I and J unless step 5 or 6, G in step 6.
std::string smc1_guarded_modules(std::uint32_t step) {
  std::string m = "A";
  if (step != 6) m += "B";
  if (step != 5 && step != 6) m += "IJ";
  if (step == 4) m += "EL";
  if (step == 6) m += "G";
  if (step == 5) m += "C";
  std::sort(m.begin(), m.end());
  return m;
}

// SMC II+ rules (cell/grafcets/smc2_plus.grafcet): A always; B unless a
// suppression runs (steps 6, 7); I and J in steps 2 and 4; D, E, H, K and
// the breakage detector N while in contact (step 4); C, the feed hold, for
// the operator (5) and a broken tool (9); G for the added pass (6); O for
// the spindle speed change (7).
std::string smc2_plus_modules(std::uint32_t step) {
  std::string m = "A";
  if (step != 6 && step != 7) m += "B";
  if (step == 2 || step == 4) m += "IJ";
  if (step == 4) m += "DEHKN";
  if (step == 5 || step == 9) m += "C";
  if (step == 6) m += "G";
  if (step == 7) m += "O";
  std::sort(m.begin(), m.end());
  return m;
}

class Supervisor {
 public:
  Supervisor(const char* file, std::string (*rules)(std::uint32_t))
      : g_(testing::load_ok(file)), engine_(g_), rules_(rules) {}

  // One evaluation with `true_inputs` (e.g. "a b") set.
  void step(const std::string& true_inputs, std::uint32_t expected_step,
            const std::string& expected_impulses = "") {
    SCOPED_TRACE("evaluation " + std::to_string(++count_) + ", inputs {" + true_inputs + "}");
    const Evaluation& r = engine_.evaluate(testing::inputs(g_, true_inputs));
    EXPECT_FALSE(r.unstable);
    ASSERT_EQ(std::popcount(r.active_steps), 1) << testing::step_numbers(g_, r.active_steps);
    const std::uint32_t step =
        engine_.step_number(static_cast<std::size_t>(std::countr_zero(r.active_steps)));
    EXPECT_EQ(step, expected_step);
    EXPECT_EQ(sorted(testing::action_names(g_, r.level_actions)), rules_(step));
    EXPECT_EQ(sorted(testing::action_names(g_, r.impulse_actions)), expected_impulses);
  }

  const Grafcet& grafcet() const { return g_; }
  Engine& engine() { return engine_; }

 private:
  static std::string sorted(std::string s) {
    std::sort(s.begin(), s.end());
    return s;
  }
  Grafcet g_;
  Engine engine_;
  std::string (*rules_)(std::uint32_t);
  int count_ = 0;
};

TEST(Smc1Supervisor, SituationsOfThePaper) {
  Supervisor s("smc1.grafcet", smc1_modules);
  // Start-up: L initialised in step 1, the situation immediately becomes 2.
  s.step("", 2, "L");
  s.step("", 2);
  // Feed hold requested and released, from step 2.
  s.step("a", 5);
  s.step("a", 5);
  s.step("", 2);
  // Contact: 2 -> 3 (L reset) -> 4 at once.
  s.step("b", 4, "L");
  s.step("b", 4);
  // Feed hold from step 4; released in contact: 5 -> 2 -> 3 -> 4, L reset again.
  s.step("a b", 5);
  s.step("a b", 5);
  s.step("b", 4, "L");
  // Feed hold from step 4, contact gone while held, released: step 2.
  s.step("a b", 5);
  s.step("a", 5);
  s.step("", 2);
  // Contact, then contact lost.
  s.step("b", 4, "L");
  s.step("", 2);
  // SMC I does not read chatter inputs.
  s.step("c d e", 2);
  s.step("b c d e", 4, "L");
  s.step("c d e", 2);
}

TEST(Smc1Supervisor, FeedHoldWinsOverContactAndContactLoss) {
  Supervisor s("smc1.grafcet", smc1_modules);
  s.step("", 2, "L");
  s.step("a b", 5);  // contact and feed hold together in step 2: (2) before (3)
  s.step("", 2);
  s.step("b", 4, "L");
  s.step("a", 5);  // contact lost and feed hold together in step 4: (5) before (7)
}

TEST(Smc1GuardedSupervisor, ChatterDetectedInContactRunsTheSuppressionThenL) {
  Supervisor s("smc1_guarded.grafcet", smc1_guarded_modules);
  // Start-up: E and L initialised in step 1, then step 2.
  s.step("", 2, "EL");
  // Contact: 2 -> 3 (E and L reset) -> 4, the cut under L watched by E.
  s.step("b", 4, "EL");
  s.step("b", 4);
  // Chatter detected: the routine G (F's rewrite, the feed held); L stops.
  s.step("b d", 6);
  s.step("b d", 6);
  // Complete while b and d are still set (J and E inactive): back through 2
  // and 3 to 4 with E and L reset; the stale d is not chatter again.
  s.step("b d e", 4, "EL");
  s.step("b", 4);
  // Complete without contact: step 2.
  s.step("b d", 6);
  s.step("d e", 2);
  // The operator's chatter signal is SMC II's (module D): not read here.
  s.step("b", 4, "EL");
  s.step("b c", 4);
  // Feed hold wins over chatter; contact loss wins over chatter.
  s.step("a b d", 5);
  s.step("b", 4, "EL");
  s.step("d", 2);
  // Chatter outside contact does nothing.
  s.step("d", 2);
  s.step("", 2);
  // A feed hold during the routine waits for its end (B is inactive).
  s.step("b", 4, "EL");
  s.step("b d", 6);
  s.step("a b", 6);
  s.step("a b e", 5);
}

TEST(Smc2Supervisor, SituationsOfThePaper) {
  Supervisor s("smc2.grafcet", smc2_modules);
  // Start-up: E and K initialised in step 1, then step 2.
  s.step("", 2, "EK");
  // Feed hold from step 2 and released.
  s.step("a", 5);
  s.step("", 2);
  // Contact: 2 -> 3 (E and K reset) -> 4.
  s.step("b", 4, "EK");
  s.step("b", 4);
  // Chatter signalled by the operator: the suppression routine G runs.
  s.step("b c", 6);
  s.step("b c", 6);
  s.step("b", 6);
  // Suppression complete while b is still set (J was inactive): back through
  // 2 and 3 to 4, E and K reset; the stale c is not chatter again.
  s.step("b c e", 4, "EK");
  s.step("b", 4);
  // Chatter detected automatically; suppression complete with contact gone.
  s.step("b d", 6);
  s.step("d", 6);
  s.step("d e", 2);
  s.step("", 2);
  // Feed hold from step 4, released in contact: 5 -> 2 -> 3 -> 4.
  s.step("b", 4, "EK");
  s.step("a b", 5);
  s.step("b", 4, "EK");
  // Feed hold from step 4 released without contact.
  s.step("a b", 5);
  s.step("", 2);
  // Contact lost.
  s.step("b", 4, "EK");
  s.step("", 2);
  // Chatter inputs outside contact do nothing.
  s.step("c d", 2);
  s.step("", 2);
}

TEST(Smc2Supervisor, Priorities) {
  Supervisor s("smc2.grafcet", smc2_modules);
  s.step("", 2, "EK");
  s.step("a b", 5);  // feed hold wins over contact (step 2)
  s.step("", 2);
  s.step("b", 4, "EK");
  s.step("a", 5);  // feed hold wins over contact loss (step 4)
  s.step("", 2);
  s.step("b", 4, "EK");
  s.step("a b d", 5);  // feed hold wins over chatter
  s.step("b", 4, "EK");
  s.step("c", 2);  // contact loss wins over chatter by the operator
  s.step("b", 4, "EK");
  s.step("d", 2);  // ... and over chatter detected automatically
  s.step("b", 4, "EK");
  s.step("b c d", 6);  // both chatter signals together: one suppression
  // B is inactive during the suppression: a feed hold waits for its end.
  s.step("a b", 6);
  s.step("a b e", 5);
}

TEST(Smc2PlusSupervisor, SpeedChangeFirstThenAddedPassAndBreakageWins) {
  Supervisor s("smc2_plus.grafcet", smc2_plus_modules);
  s.step("", 2, "EKN");
  s.step("b", 4, "EK");
  // First automatic chatter of the pass: the spindle speed change (7).
  s.step("b d", 7);
  s.step("b d", 7);
  // At speed: E and K reset at the new speed (8), back in the cut.
  s.step("b d g", 4, "EK");
  // The core now says this pass had its speed change (h): the next chatter
  // adds a pass (6), as SMC II.
  s.step("b h", 4);
  s.step("b d h", 6);
  // Complete with contact still set: through 2 and 3 to 4, E and K reset.
  s.step("b d e h", 4, "EK");
  s.step("b", 4);
  // The operator's chatter signal always adds a pass.
  s.step("b c", 6);
  s.step("b c e", 4, "EK");
  s.step("b", 4);
  // A breakage from the cut: feed held (9) and stays so while f is latched,
  // whatever else comes.
  s.step("b f", 9);
  s.step("b d f", 9);
  s.step("a b c f", 9);
  s.step("f", 9);
  // The operator's hold wins over a breakage seen in the same evaluation;
  // released, the breakage takes over.
  s.step("", 2);
  s.step("a f", 5);
  s.step("f", 9);
  // A breakage during a speed change.
  s.step("", 2);
  s.step("b", 4, "EK");
  s.step("b d", 7);
  s.step("b f", 9);
}

// Random input sequences: the rules hold at every evaluation.
TEST(Smc2Supervisor, RulesHoldOnRandomInputSequences) {
  for (const char* file :
       {"smc1.grafcet", "smc1_guarded.grafcet", "smc2.grafcet", "smc2_plus.grafcet"}) {
    const Grafcet g = testing::load_ok(file);
    Engine e(g);
    auto rules = std::string(file) == "smc1.grafcet"           ? smc1_modules
                 : std::string(file) == "smc1_guarded.grafcet" ? smc1_guarded_modules
                 : std::string(file) == "smc2_plus.grafcet"    ? smc2_plus_modules
                                                               : smc2_modules;
    std::mt19937_64 rng(12345);
    Mask in = 0;
    for (int i = 0; i < 20000; ++i) {
      in ^= (rng() & rng()) & ((Mask{1} << g.inputs().size()) - 1);  // a few bits change
      const Evaluation& r = e.evaluate(in);
      ASSERT_FALSE(r.unstable);
      ASSERT_EQ(std::popcount(r.active_steps), 1);
      const std::uint32_t step =
          e.step_number(static_cast<std::size_t>(std::countr_zero(r.active_steps)));
      std::string modules = testing::action_names(g, r.level_actions);
      std::sort(modules.begin(), modules.end());
      ASSERT_EQ(modules, rules(step)) << file << " step " << step << " at evaluation " << i;
    }
  }
}

TEST(Smc2Supervisor, PrintedLevelReceptivitiesCycle) {
  // The receptivities as printed (c + d, e): after a suppression with b, c
  // and e still set, 2 -> 3 -> 4 -> 6 -> 2 ... never settles.
  const Grafcet g = testing::load_ok("broken/smc2_printed.grafcet");
  Engine e(g);
  e.evaluate(0);
  e.evaluate(testing::inputs(g, "b"));
  EXPECT_EQ(testing::step_numbers(g, e.evaluate(testing::inputs(g, "b c")).active_steps), "6");
  const Evaluation& r = e.evaluate(testing::inputs(g, "b c e"));
  EXPECT_TRUE(r.unstable);
  EXPECT_EQ(r.rounds, kDefaultMaxRounds);
}

}  // namespace
}  // namespace smc::grafcet
