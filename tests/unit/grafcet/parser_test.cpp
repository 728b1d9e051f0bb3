// The text format: expressions in every accepted notation, the model built
// from a file, and errors with their exact places.

#include "smc/grafcet/parser.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "grafcet_test_util.hpp"

namespace smc::grafcet {
namespace {

using testing::parse_ok;

// A Grafcet with inputs a..e and step 1..3 whose transition (1) carries the
// receptivity under test.
std::string with_receptivity(const std::string& receptivity) {
  return "input a, b, c, d, e\nstep 1 initial\nstep 2\nstep 3\n"
         "transition 1: 1 -> 2 when " +
         receptivity + "\ntransition 2: 2 -> 1 when 1\n";
}

// Truth table of transition (1)'s receptivity over a..e and X1..X3.
std::vector<bool> truth_table(const std::string& receptivity) {
  const Grafcet g = parse_ok(with_receptivity(receptivity));
  std::vector<bool> table;
  for (Mask in = 0; in < 32; ++in)
    for (Mask steps = 0; steps < 8; ++steps)
      for (Mask rise = 0; rise < 4; ++rise) {
        Context ctx{in, rise, rise << 2, steps, 0, 0};
        table.push_back(evaluate(g.transitions()[0].receptivity, ctx));
      }
  return table;
}

std::vector<bool> reference(bool (*f)(Mask in, Mask steps, Mask rise)) {
  std::vector<bool> table;
  for (Mask in = 0; in < 32; ++in)
    for (Mask steps = 0; steps < 8; ++steps)
      for (Mask rise = 0; rise < 4; ++rise) table.push_back(f(in, steps, rise));
  return table;
}

bool bit(Mask m, int i) { return (m >> i & 1u) != 0; }

TEST(GrafcetExpression, PaperNotationAndCNotationAgree) {
  // a b'  (the paper), a·b', a && !b, a & ~b, a ∧ ¬b, a b’ (typographic prime)
  const auto expected = reference([](Mask in, Mask, Mask) { return bit(in, 0) && !bit(in, 1); });
  for (const char* text : {"a b'", "a·b'", "a && !b", "a & ~b", "a ∧ ¬b", "a b’", "(a)(b')"})
    EXPECT_EQ(truth_table(text), expected) << text;
}

TEST(GrafcetExpression, OrNotationsAgree) {
  const auto expected = reference([](Mask in, Mask, Mask) { return bit(in, 2) || bit(in, 3); });
  for (const char* text : {"c + d", "c || d", "c | d", "c ∨ d", "(c + d)''"})
    EXPECT_EQ(truth_table(text), expected) << text;
  const auto negated = reference([](Mask in, Mask, Mask) { return !(bit(in, 2) || bit(in, 3)); });
  for (const char* text : {"(c + d)'", "!(c || d)", "c' d'", "~c & !d"})
    EXPECT_EQ(truth_table(text), negated) << text;
}

TEST(GrafcetExpression, PrecedenceAndConstants) {
  EXPECT_EQ(truth_table("a + b c"), reference([](Mask in, Mask, Mask) {
              return bit(in, 0) || (bit(in, 1) && bit(in, 2));
            }));
  EXPECT_EQ(truth_table("!a b"),
            reference([](Mask in, Mask, Mask) { return !bit(in, 0) && bit(in, 1); }));
  EXPECT_EQ(truth_table("!a'"), reference([](Mask in, Mask, Mask) { return bit(in, 0); }));
  EXPECT_EQ(truth_table("1"), reference([](Mask, Mask, Mask) { return true; }));
  EXPECT_EQ(truth_table("0"), reference([](Mask, Mask, Mask) { return false; }));
  EXPECT_EQ(truth_table("a -> b"),
            reference([](Mask in, Mask, Mask) { return !bit(in, 0) || bit(in, 1); }));
  EXPECT_EQ(truth_table("a <-> b + c"), reference([](Mask in, Mask, Mask) {
              return bit(in, 0) == (bit(in, 1) || bit(in, 2));
            }));
  EXPECT_EQ(truth_table("a ↔ b"),
            reference([](Mask in, Mask, Mask) { return bit(in, 0) == bit(in, 1); }));
}

TEST(GrafcetExpression, StepVariablesAndEdges) {
  EXPECT_EQ(truth_table("X3 + X1 a"), reference([](Mask in, Mask s, Mask) {
              return bit(s, 2) || (bit(s, 0) && bit(in, 0));
            }));
  // rise: bits 0..1 (a, b); fall: bits 2..3 (c, d) in the truth-table context
  EXPECT_EQ(truth_table("↑a + rise(b)"),
            reference([](Mask, Mask, Mask r) { return bit(r, 0) || bit(r, 1); }));
  EXPECT_EQ(truth_table("↓c ↓d'"),
            reference([](Mask, Mask, Mask r) { return bit(r << 2, 2) && !bit(r << 2, 3); }));
  EXPECT_EQ(truth_table("fall(c)"), reference([](Mask, Mask, Mask r) { return bit(r, 0); }));
}

TEST(GrafcetParser, BuildsTheModelOfSmc2) {
  const Grafcet g = testing::load_ok("smc2.grafcet");
  EXPECT_EQ(g.name(), "smc2");
  ASSERT_EQ(g.inputs().size(), 5u);
  EXPECT_EQ(g.input_index("a"), 0);
  EXPECT_EQ(g.input_index("e"), 4);
  ASSERT_EQ(g.steps().size(), 6u);
  for (std::uint32_t n = 1; n <= 6; ++n) EXPECT_EQ(g.step_index(n), static_cast<int>(n - 1));
  EXPECT_EQ(g.initial_steps(), Mask{1});
  EXPECT_TRUE(g.steps()[0].initial);
  const int e = g.action_index("E");
  const int k = g.action_index("K");
  ASSERT_GE(e, 0);
  ASSERT_GE(k, 0);
  const Mask ek = (Mask{1} << e) | (Mask{1} << k);
  EXPECT_EQ(g.steps()[0].impulse_actions, ek);
  EXPECT_EQ(g.steps()[2].impulse_actions, ek);
  EXPECT_EQ(g.steps()[0].level_actions, 0u);
  EXPECT_EQ(testing::action_names(g, g.steps()[3].level_actions).size(), 8u);  // ABDEHIJK
  ASSERT_EQ(g.transitions().size(), 9u);
  const Transition& t6 = g.transitions()[static_cast<std::size_t>(g.transition_index(6))];
  EXPECT_EQ(t6.preceding, Mask{1} << 3);
  EXPECT_EQ(t6.following, Mask{1} << 5);
  EXPECT_EQ(t6.receptivity.text, "↑c + ↑d");
  ASSERT_EQ(g.orders().size(), 2u);
  const CheckingOrder& from4 = g.orders()[1];
  EXPECT_EQ(from4.step, 3u);
  ASSERT_EQ(from4.transitions.size(), 3u);
  EXPECT_EQ(g.transitions()[from4.transitions[0]].number, 5u);
  EXPECT_EQ(g.transitions()[from4.transitions[1]].number, 7u);
  EXPECT_EQ(g.transitions()[from4.transitions[2]].number, 6u);
  EXPECT_FALSE(g.invariants().empty());
}

TEST(GrafcetParser, StatementsSpanLinesWithBackslashAndTakeComments) {
  const Grafcet g = parse_ok(
      "grafcet t \"title\"   # comment\n"
      "input a \"first\", b\n"
      "step 1 initial \"start\": A, B* C   # mixed separators\n"
      "step 2\n"
      "transition (1): 1 -> 2 when a \\\n"
      "    + b   # continued\n"
      "transition 2: 2 -> 1 when 1\n"
      "invariant \"n\": A -> \\\n"
      "  next X2 + X1\n");
  EXPECT_EQ(g.title(), "title");
  EXPECT_EQ(g.inputs()[0].description, "first");
  EXPECT_EQ(g.steps()[0].label, "start");
  EXPECT_EQ(testing::action_names(g, g.steps()[0].level_actions), "AC");
  EXPECT_EQ(testing::action_names(g, g.steps()[0].impulse_actions), "B");
  EXPECT_EQ(g.transitions()[0].receptivity.text, "a + b");
  ASSERT_TRUE(g.invariants()[0].next.has_value());
  EXPECT_EQ(g.invariants()[0].condition.text, "A");
  EXPECT_EQ(g.invariants()[0].next->text, "X2 + X1");
}

TEST(GrafcetParser, ReadmeExampleParses) {
  std::ostringstream buffer;
  buffer << std::ifstream(std::string(SMC_SOURCE_DIR) + "/services/grafcet/README.md").rdbuf();
  const std::string readme = buffer.str();
  const std::size_t begin = readme.find("grafcet smc2 \"");
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = readme.find("```", begin);
  ASSERT_NE(end, std::string::npos);
  const Grafcet g = parse_ok(readme.substr(begin, end - begin));
  EXPECT_EQ(g.steps().size(), 6u);
  EXPECT_EQ(g.invariants().size(), 4u);
}

TEST(GrafcetParser, NameDefaultsToTheFileStem) {
  ParseResult r = parse("step 1 initial\n", "dir/my_supervisor.grafcet");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.grafcet->name(), "my_supervisor");
}

struct Expected {
  std::uint32_t line;
  std::uint32_t column;
  std::string fragment;  // part of the message
};

void expect_errors(const std::string& text, const std::vector<Expected>& expected) {
  const ParseResult r = parse(text, "bad.grafcet");
  EXPECT_FALSE(r.ok());
  EXPECT_FALSE(r.grafcet.has_value()) << "a half-parsed Grafcet must never be returned";
  std::string all;
  for (const Diagnostic& d : r.errors) all += d.str() + "\n";
  ASSERT_EQ(r.errors.size(), expected.size()) << all;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(r.errors[i].location.line, expected[i].line) << all;
    EXPECT_EQ(r.errors[i].location.column, expected[i].column) << all;
    EXPECT_NE(r.errors[i].message.find(expected[i].fragment), std::string::npos)
        << "message: " << r.errors[i].message << "\nexpected to contain: " << expected[i].fragment;
    EXPECT_EQ(r.errors[i].file, "bad.grafcet");
  }
}

// Found by fuzz_grafcet: 4,000 nested '(' overflowed the parser's stack.
// Nesting and depth are bounded; within the bounds an expression parses and
// evaluates as written.
TEST(GrafcetParserErrors, ExpressionsNestedTooDeepAreRefusedNotAStackOverflow) {
  const auto receptivity_errors = [](const std::string& r) {
    const ParseResult res = parse(with_receptivity(r), "deep.grafcet");
    std::string all;
    for (const Diagnostic& d : res.errors) all += d.str() + "\n";
    return all;
  };
  EXPECT_NE(receptivity_errors(std::string(4000, '(') + "a" + std::string(4000, ')'))
                .find("nested more than 100 levels deep"),
            std::string::npos);
  EXPECT_NE(receptivity_errors(std::string(4000, '!') + "a").find("nested more than 100"),
            std::string::npos);
  std::string chain = "a";
  for (int i = 0; i < 600; ++i) chain += " & b";
  EXPECT_NE(receptivity_errors(chain).find("more than 500 operators deep"), std::string::npos);
  std::string primes = "a" + std::string(600, '\'');
  EXPECT_NE(receptivity_errors(primes).find("more than 500 operators deep"), std::string::npos);

  // At the bounds: accepted, and evaluated as written (100 '(' around a & b;
  // 99 '!' = one '!'; a chain of 400 '&').
  const auto truth = [](const std::string& r) { return truth_table(r); };
  EXPECT_EQ(truth(std::string(100, '(') + "a & b" + std::string(100, ')')), truth("a & b"));
  EXPECT_EQ(truth(std::string(99, '!') + "a"), truth("!a"));
  std::string long_chain = "a";
  for (int i = 0; i < 400; ++i) long_chain += " & b";
  EXPECT_EQ(truth(long_chain), truth("a & b"));
}

TEST(GrafcetParserErrors, EveryErrorOfAFileIsReportedWithItsPlace) {
  expect_errors(
      "input a, b\n"                             // 1
      "step 1 initial: L*\n"                     // 2
      "stpe 2: A\n"                              // 3  unknown statement
      "step 3: A\n"                              // 4
      "transition 1: 1 -> 3 when a +\n"          // 5  operand missing at end of line
      "transition 2: 3 -> 9 when b\n"            // 6  no step 9
      "transition 3: 3 -> 1 whn b\n"             // 7  'when' misspelt
      "transition 4: 3 -> 1 when q & A\n"        // 8  unknown q, action A in a receptivity
      "invariant \"x\": L* -> next X1\n"         // 9  impulse in the condition
      "invariant \"y\": a -> (b -> next X3)\n",  // 10 next nested
      {
          {3, 1, "expected a statement"},
          {5, 30, "expected an operand"},
          {6, 20, "no step 9"},
          {7, 22, "expected 'when'"},
          {8, 27, "unknown name 'q'"},
          {8, 31, "'A' is an action"},
          {9, 16, "'L*' (impulse fired)"},
          {10, 27, "'next' is allowed only"},
      });
}

TEST(GrafcetParserErrors, LexicalErrors) {
  expect_errors(
      "input a\n"
      "step 1 initial \"unterminated\n"
      "step 2\n"
      "transition 1: 1 -> 2 when a = 1\n"
      "transition 2: 2 -> 1 when a $\n",
      {
          {2, 16, "unterminated string"},
          {4, 29, "write '<->'"},
          {5, 29, "unexpected character '$'"},
      });
}

TEST(GrafcetParserErrors, ColumnsCountCharactersNotBytes) {
  // '↑' and '·' are several bytes each; the 7 is character 36 (byte 40).
  expect_errors(
      "input a, b\nstep 1 initial\nstep 2\n"
      "transition 1: 1 -> 2 when ↑a · b · 7\n",
      {{4, 36, "expected the constant 0 or 1"}});
}

TEST(GrafcetParserErrors, StructureErrors) {
  expect_errors(
      "input a, a\n"                      // 1 duplicate input
      "input X3, when\n"                  // 2 reserved names
      "step 1: A\n"                       // 3
      "step 1: B\n"                       // 4 duplicate step
      "step 2: a\n"                       // 5 action named like an input
      "step 3: C, C\n"                    // 6 action twice
      "transition 1: 1 -> 2 when a\n"     // 7
      "transition 1: 2 -> 1 when 1\n"     // 8 duplicate transition
      "transition 2: 2, 2 -> 1 when 1\n"  // 9 step twice
      "transition 3: 2 -> 3 when !a\n"    // 10
      "order 2: 2\n"                      // 11 (3) missing
      "order 1: 2\n"                      // 12 (2) does not leave step 1
      "order 7: 1\n"                      // 13 no step 7
      "invariant \"i\": 1\n"              // 14
      "invariant \"i\": 1\n"              // 15 duplicate invariant
      "grafcet again\n",                  // 16 no 'grafcet' before: fine; then none
      {
          {1, 10, "already declared"},
          {2, 7, "'X3' cannot name an input"},
          {2, 11, "keyword"},
          {3, 6, "no initial step"},
          {4, 6, "step 1 is already declared"},
          {5, 9, "'a' is an input"},
          {6, 12, "listed twice for step 3"},
          {8, 12, "transition (1) is already declared"},
          {9, 18, "listed twice among the preceding steps"},
          {11, 1, "(3) is missing"},
          {12, 10, "does not leave step 1"},
          {13, 7, "no step 7"},
          {15, 1, "already declared"},
      });
}

TEST(GrafcetParserErrors, SecondGrafcetStatementAndNoSteps) {
  expect_errors("grafcet one\ngrafcet two\n",
                {{1, 1, "has no step"}, {2, 1, "a second 'grafcet' statement"}});
}

TEST(GrafcetParserErrors, LimitsAreEnforcedAtParseTime) {
  std::string steps = "step 0 initial\n";
  for (int i = 1; i <= 64; ++i) steps += "step " + std::to_string(i) + "\n";
  expect_errors(steps, {{65, 6, "too many steps: at most 64"}});

  std::string inputs = "step 1 initial\n";
  for (int i = 0; i <= 64; ++i) inputs += "input i" + std::to_string(i) + "\n";
  expect_errors(inputs, {{66, 7, "too many inputs: at most 64"}});

  std::string actions = "step 1 initial:";
  for (int i = 0; i <= 64; ++i) actions += " A" + std::to_string(i);
  // " A64", the 65th action, starts at column 263.
  expect_errors(actions + "\n", {{1, 263, "too many actions"}});
}

TEST(GrafcetParserErrors, ExpressionDepthAndNumbers) {
  std::string deep;
  for (int i = 0; i < 70; ++i) deep += "a & (";
  deep += "a";
  for (int i = 0; i < 70; ++i) deep += ")";
  expect_errors("input a\nstep 1 initial\ntransition 1: 1 -> 1 when " + deep + "\n",
                {{3, 27, "too deeply nested"}});
  expect_errors("step 99999999999 initial\n", {{1, 6, "too large"}});
}

TEST(GrafcetParserErrors, DiagnosticFormatAndUnreadableFile) {
  const ParseResult r = parse("step 1 initial\nstep x\n", "f.grafcet");
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].str(),
            "f.grafcet:2:6: error: expected a step number after 'step', found name 'x'");
  const ParseResult missing = parse_file("/nonexistent/dir/none.grafcet");
  ASSERT_EQ(missing.errors.size(), 1u);
  EXPECT_EQ(missing.errors[0].location.line, 0u);
  EXPECT_EQ(missing.errors[0].str(), "/nonexistent/dir/none.grafcet: error: cannot open the file");
}

TEST(GrafcetParserErrors, SyntaxErrorInAStepDoesNotCascade) {
  // Step 2 is broken, but transitions naming it must not add "no step 2".
  expect_errors(
      "input a\nstep 1 initial\nstep 2 \"x\" A\ntransition 1: 1 -> 2 when a\n"
      "transition 2: 2 -> 1 when a'\n",
      {{3, 12, "end of line after the step's label"}});
}

}  // namespace
// Issue: a 10 MB garbage Grafcet gave 40 MB of errors.
TEST(GrafcetParserErrors, GarbageGivesABoundedReport) {
  std::string garbage;
  for (int i = 0; garbage.size() < 10'000'000; ++i)
    garbage += "step ?? when !!! -> ((( " + std::to_string(i) + "\n";
  const ParseResult r = parse(garbage, "garbage.grafcet");
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), kMaxErrors + 1);
  EXPECT_NE(r.errors.back().message.find(" more errors"), std::string::npos);
  std::size_t printed = 0;
  for (const auto& d : r.errors) printed += d.str().size();
  EXPECT_LT(printed, 64u * 1024);
}

}  // namespace smc::grafcet
