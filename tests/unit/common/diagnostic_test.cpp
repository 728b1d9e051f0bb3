#include "smc/common/diagnostic.hpp"

#include <gtest/gtest.h>

#include <string>

namespace smc::common {
namespace {

TEST(Diagnostic, OneLineWithWhereMessageAndFix) {
  const Diagnostic d{"job.textproto:3:7", "depth_mm: -3 mm is negative\nsecond line", "give > 0"};
  EXPECT_EQ(d.str(), "job.textproto:3:7: depth_mm: -3 mm is negative second line; fix: give > 0");
  EXPECT_EQ((Diagnostic{"x", "bad", ""}).str(), "x: bad");
}

TEST(Diagnostics, BoundedWithCountOfTheRest) {
  Diagnostics l;
  for (int i = 0; i < 25; ++i) l.add("f:" + std::to_string(i + 1) + ":1", "bad");
  const std::string s = l.str(3);
  EXPECT_NE(s.find("f:3:1: bad"), std::string::npos);
  EXPECT_EQ(s.find("f:4:1"), std::string::npos);
  EXPECT_NE(s.find("and 22 more problems"), std::string::npos);
  EXPECT_EQ(l.size(), 25u);
}

TEST(DiagnosticError, CarriesTheListAndItsText) {
  Diagnostics l;
  l.add("a", "one");
  l.add("b", "two", "do this");
  const DiagnosticError e(l);
  EXPECT_EQ(std::string(e.what()), "a: one\nb: two; fix: do this");
  EXPECT_EQ(e.diagnostics().size(), 2u);
}

TEST(Quote, EscapesAndBounds) {
  EXPECT_EQ(quote("ab"), "'ab'");
  EXPECT_EQ(quote("a\nb\x01'"), "'a\\nb\\x01\\''");
  const std::string big(10'000'000, 'x');
  const std::string q = quote(big, 8);
  EXPECT_EQ(q, "'xxxxxxxx'…(10000000 bytes)");
}

TEST(Number, ShortestThatReadsBack) {
  EXPECT_EQ(number(0.1), "0.1");
  EXPECT_EQ(number(745.7), "745.7");
  EXPECT_EQ(number(1e-12), "1e-12");
  EXPECT_EQ(number(4.9406564584124654e-324), "5e-324");
}

}  // namespace
}  // namespace smc::common
