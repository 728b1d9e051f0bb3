#include "smc/grafcet/dot.hpp"

#include <gtest/gtest.h>

#include <string>

#include "grafcet_test_util.hpp"

namespace smc::grafcet {
namespace {

TEST(GrafcetDot, DrawsStepsActionsAndTransitions) {
  const Grafcet g = testing::load_ok("smc2.grafcet");
  const std::string dot = to_dot(g);
  EXPECT_EQ(dot.rfind("digraph \"smc2\" {", 0), 0u) << dot;
  EXPECT_NE(dot.find("s1 [shape=box, width=0.5, height=0.5, label=\"1\", peripheries=2"),
            std::string::npos)
      << dot;
  for (int s = 2; s <= 6; ++s)
    EXPECT_NE(dot.find(std::string("s").append(std::to_string(s)).append(" [shape=box")),
              std::string::npos)
        << s;
  EXPECT_NE(dot.find("s1_act [shape=record, fontsize=11, label=\"E* | K*\"]"), std::string::npos)
      << dot;
  EXPECT_NE(dot.find("(6) ↑c + ↑d  [3 from 4]"), std::string::npos) << dot;
  EXPECT_NE(dot.find("(7) b'  [2 from 4]"), std::string::npos) << dot;
  EXPECT_NE(dot.find("s4 -> t6;"), std::string::npos);
  EXPECT_NE(dot.find("t6 -> s6;"), std::string::npos);
  EXPECT_NE(dot.find("t9 -> s2 [arrowhead=normal"), std::string::npos);  // back up the chart
  EXPECT_EQ(dot.back(), '\n');
}

}  // namespace
}  // namespace smc::grafcet
