// The chatter study's figures draw what the study counted.

#include "chatter_plots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

using smc::bench::ChatterStudyFigures;

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

ChatterStudyFigures study() {
  ChatterStudyFigures f;
  f.subtitle = "a made-up study";
  auto cut = [&](double rpm, double width, double runout, bool unstable, double delay,
                 double level) {
    ChatterStudyFigures::Cut c;
    c.rpm = rpm;
    c.width = width;
    c.runout = runout;
    c.unstable = unstable;
    c.detected = !std::isnan(delay);
    c.delay_revs = delay;
    c.level = level;
    f.cuts.push_back(c);
  };
  cut(1500, 25, 0, true, 1.0, 0.151);   // within 3
  cut(1500, 37, 10, true, 5.0, 0.180);  // late
  cut(2500, 50, 20, true, 25.0, 0.32);  // later than the plot's 10: drawn above it
  cut(2500, 25, 0, true, NAN, 0.155);   // missed
  cut(1500, 50, 0, false, 0, 0.149);
  cut(2500, 37, 10, false, 0, 0.05);  // below the margin plot's range
  // Decided 41 revolutions before the onset, where the mill's q had not
  // reached it: a false detection, neither detected nor missed.
  cut(2000, 50, 10, true, -41.0, 0.152);
  f.cuts.back().premature = true;
  f.cuts.back().detected = false;
  // A period doubling's onset, which q did not see: its level is not q's,
  // and the margin neither draws it nor counts it.
  cut(2000, 50, 0, true, 2.0, 0.02);
  f.cuts.back().by_flip = true;
  f.unstable = 6;
  f.e_false = 1;
  f.e_late = 3;
  for (int i = 0; i < 4000; ++i) {
    const double q = 0.05 + 0.3 * i / 4000.0;
    f.q_pairs.push_back({1500, q, 1.05 * q});
  }
  f.q_pairs.push_back({1500, 0.01, 0.02});  // below the drawn range: not counted
  for (const double sigma : {0.0, 0.01, 0.1}) {
    ChatterStudyFigures::ErrorRow r;
    r.sigma = sigma;
    r.false_mean = 100 * sigma;
    r.false_lo = static_cast<int>(80 * sigma);
    r.false_hi = static_cast<int>(120 * sigma);
    f.error_rows.push_back(r);
  }
  return f;
}

TEST(ChatterStudyFigures, DrawWhatTheStudyCounted) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "chatter-figures";
  std::filesystem::remove_all(dir);
  const auto paths = smc::bench::write_chatter_figures(dir, study());
  ASSERT_EQ(paths.size(), 4u);
  for (const auto& p : paths) EXPECT_TRUE(std::filesystem::exists(p)) << p;

  const std::string delay = read(dir / "chatter-delay.svg");
  EXPECT_NE(delay.find("E: 2 of 6 unstable cuts within 3 revolutions of the onset, 4 detected, "
                       "1 false detections"),
            std::string::npos);
  EXPECT_NE(delay.find("later than 10 revolutions (1)"), std::string::npos);
  EXPECT_NE(delay.find("missed (1)"), std::string::npos);
  EXPECT_NE(delay.find("before the onset, the mill&apos;s q below it: false (1)"),
            std::string::npos);
  EXPECT_NE(delay.find("the label&apos;s onset (below: E decided before it)"), std::string::npos);
  EXPECT_NE(delay.find("the goal: 3 revolutions"), std::string::npos);
  EXPECT_NE(delay.find("widths 25, 37, 50 mm"), std::string::npos);
  EXPECT_NE(delay.find(">a made-up study<"), std::string::npos);

  const std::string margin = read(dir / "chatter-margin.svg");
  EXPECT_NE(
      margin.find("stable cuts&apos; onset levels up to 0.1490, unstable cuts&apos; from 0.1510"),
      std::string::npos);
  EXPECT_NE(margin.find("not drawn: outside 0.10-0.20 1 stable, 1 unstable cuts, and 1 period "
                        "doublings"),
            std::string::npos);
  EXPECT_NE(margin.find("stable: the largest level (1)"), std::string::npos);
  EXPECT_NE(margin.find("unstable: the onset&apos;s level (4)"), std::string::npos);

  const std::string estimate = read(dir / "chatter-estimate.svg");
  // 4000 pairs at one speed, every eighth drawn.
  EXPECT_NE(estimate.find("500 of 4000 drawn"), std::string::npos);
  EXPECT_NE(estimate.find("1500 rpm (4000)"), std::string::npos);

  const std::string error = read(dir / "chatter-error.svg");
  EXPECT_NE(error.find("(6 unstable cuts)"), std::string::npos);
  EXPECT_NE(error.find("E: 3 not within 3 revolutions"), std::string::npos);
  EXPECT_NE(error.find("E: 1 false detections"), std::string::npos);
  // Three rows: three bars for each of the two counts.
  EXPECT_EQ(count(error, "stroke-width=\"3.00\""), 6u);
}

TEST(ChatterStudyFigures, ADirectoryThatCannotBeMadeIsNamed) {
  const auto file = std::filesystem::path(::testing::TempDir()) / "chatter-figures-a-file";
  std::ofstream(file) << "not a directory";
  try {
    smc::bench::write_chatter_figures(file / "figures", study());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((file / "figures").string()), std::string::npos)
        << e.what();
  }
}

}  // namespace
