// smc_common's SVG plot and CSV writers (used by smc-cell lobes and tds).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "smc/common/csv.hpp"
#include "smc/common/svg_plot.hpp"

namespace {

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("smc_plot_test_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

TEST(NiceTicks, CoverTheRangeWithRoundSteps) {
  EXPECT_EQ(smc::plot::nice_ticks(0, 10, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(smc::plot::nice_ticks(750, 3000, 6),
            (std::vector<double>{1000, 1500, 2000, 2500, 3000}));
  const auto t = smc::plot::nice_ticks(-0.37, 0.52, 6);
  ASSERT_FALSE(t.empty());
  EXPECT_DOUBLE_EQ(t.front(), -0.2);
  EXPECT_TRUE(smc::plot::nice_ticks(1, 1).empty());
  EXPECT_TRUE(smc::plot::nice_ticks(0, std::nan("")).empty());
  EXPECT_EQ(smc::plot::format_tick(0.25, 0.25), "0.25");
  EXPECT_EQ(smc::plot::format_tick(1500, 500), "1500");
  EXPECT_EQ(smc::plot::format_tick(0.4, 0.2), "0.4");
}

TEST(SvgPlot, WritesSeriesLegendReferencesAndEscapedText) {
  smc::plot::Figure fig("F_Y <SMC I> & more");
  fig.x_axis().label = "time (s)";
  fig.y_axis().label = "F_Y (N)";
  std::vector<double> t, y;
  for (int i = 0; i < 100; ++i) {
    t.push_back(i * 0.04);
    y.push_back(i == 50 ? std::nan("") : 200 + 20 * std::sin(i * 0.3));
  }
  fig.add_line("F_Y", t, y);
  fig.add_scatter("chatter", {1.0, 2.0}, {230, 240}).marker = smc::plot::Marker::square;
  fig.add_horizontal(190, "F_ref");
  fig.add_vertical(2.5, "feed hold");
  const std::string svg = fig.svg();
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("F_Y &lt;SMC I&gt; &amp; more"), std::string::npos);
  EXPECT_EQ(count(svg, "<polyline"), 2u);                       // the NaN splits the line
  EXPECT_EQ(count(svg, "width=\"7.00\" height=\"7.00\""), 3u);  // 2 markers + the legend's
  EXPECT_NE(svg.find(">F_ref<"), std::string::npos);
  EXPECT_NE(svg.find(">feed hold<"), std::string::npos);
  EXPECT_NE(svg.find(">chatter<"), std::string::npos);
  EXPECT_NE(svg.find(">time (s)<"), std::string::npos);
  EXPECT_EQ(svg, fig.svg());  // deterministic
  const auto file = temp("plot.svg");
  fig.write(file);
  EXPECT_EQ(read(file), svg);
  std::filesystem::remove(file);
  EXPECT_THROW(fig.write("/nonexistent/dir/plot.svg"), std::runtime_error);
}

TEST(SvgPlot, ASubtitleSitsUnderTheTitleAndThePlotMovesDown) {
  smc::plot::Figure fig("E's delay");
  fig.add_scatter("cuts", {1.0, 2.0}, {3.0, 4.0});
  const std::string without = fig.svg();
  EXPECT_NE(without.find("<rect x=\"72.00\" y=\"40.00\""), std::string::npos);
  fig.set_subtitle("2 seeds, runouts 0 & 20 um");
  const std::string with = fig.svg();
  EXPECT_NE(with.find("fill=\"#555555\">2 seeds, runouts 0 &amp; 20 um</text>"), std::string::npos);
  // The plot area starts a line lower, under the subtitle.
  EXPECT_NE(with.find("<rect x=\"72.00\" y=\"58.00\""), std::string::npos);
}

TEST(SvgPlot, ThinsLongLinesButKeepsTheirPeaks) {
  smc::plot::Figure fig;
  fig.set_size(400, 300).set_max_points_per_series(200);
  std::vector<double> t, y;
  for (int i = 0; i < 100000; ++i) {
    t.push_back(i * 1e-4);
    y.push_back(i == 77777 ? 1000.0 : std::sin(i * 0.01));
  }
  fig.add_line("long", t, y);
  fig.y_axis().min = -2;
  fig.y_axis().max = 1100;
  const std::string svg = fig.svg();
  EXPECT_LT(svg.size(), 200000u);
  // The spike's y pixel (near the top) is still drawn.
  // y = 1000 maps to top + (1100 - 1000) / 1102 * plot height.
  const double py = 20 + (1100.0 - 1000.0) / 1102.0 * (300 - 20 - 56);  // no title: top 20
  char needle[32];
  std::snprintf(needle, sizeof needle, ",%.2f", py);
  EXPECT_NE(svg.find(needle), std::string::npos) << needle;
}

TEST(Csv, WritesColumnsAndQuotesText) {
  const auto file = temp("out.csv");
  {
    smc::csv::Writer w(file, {"time_s", "label, with comma"});
    w.field(0.5).field("a \"quoted\" word");
    w.end_row();
    w.row({1e-5, std::nan("")});
    w.close();
  }
  EXPECT_EQ(read(file), "time_s,\"label, with comma\"\n0.5,\"a \"\"quoted\"\" word\"\n1e-05,\n");
  const std::vector<double> a{1, 2}, b{3, 4};
  smc::csv::write_columns(file, {"a", "b"}, {&a, &b});
  EXPECT_EQ(read(file), "a,b\n1,3\n2,4\n");
  const std::vector<double> c{1};
  EXPECT_THROW(smc::csv::write_columns(file, {"a", "c"}, {&a, &c}), std::invalid_argument);
  std::filesystem::remove(file);
  EXPECT_THROW(smc::csv::Writer("/nonexistent/dir/x.csv", {"a"}), std::runtime_error);
}
