#pragma once
// A small SVG plot writer: line and scatter series on linear axes, with
// ticks, axis labels, a title (and a subtitle under it), a legend, vertical marker lines and
// horizontal reference lines, each optionally labelled. Self-contained (no dependencies),
// deterministic output, text escaped.
//
//   smc::plot::Figure fig("F_Y with SMC I");
//   fig.x_axis().label = "time (s)";
//   fig.y_axis().label = "F_Y (N)";
//   fig.add_line("F_Y", t, fy);
//   fig.add_horizontal(190.0, "F_ref");
//   fig.add_vertical(12.3, "feed hold");
//   fig.write("fy.svg");
//
// A NaN in x or y breaks a line (a gap). Long line series are thinned for
// drawing to at most max_points_per_series by keeping each pixel column's
// first, lowest, highest and last points, so peaks survive.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace smc::plot {

enum class Style { line, markers, line_and_markers };
enum class Marker { circle, square, triangle, diamond, cross };
enum class LegendPosition { top_right, top_left, bottom_right, bottom_left, none };

struct Series {
  std::string label;  // legend entry; empty: not in the legend
  std::vector<double> x;
  std::vector<double> y;
  Style style = Style::line;
  std::string color;  // any SVG colour; empty: the next palette colour
  double line_width = 1.5;
  bool dashed = false;
  Marker marker = Marker::circle;
  double marker_size = 3.5;  // radius-like, px
  bool filled = true;        // marker filled or outlined
};

// A vertical line at x = value or a horizontal line at y = value, across
// the plot area, with its label at the top (vertical) or right end
// (horizontal).
struct Reference {
  double value = 0;
  std::string label;
  std::string color = "#666666";
  bool dashed = true;
  double line_width = 1.0;
};

struct Axis {
  std::string label;
  std::optional<double> min;  // default: from the data and the reference lines
  std::optional<double> max;
  bool include_zero = false;  // stretch the automatic range to include 0
  int tick_target = 6;        // about this many ticks
};

class Figure {
 public:
  explicit Figure(std::string title = {});

  Figure& set_title(std::string title);
  // A second line under the title, smaller and grey: what was run, say.
  Figure& set_subtitle(std::string subtitle);
  Figure& set_size(int width_px, int height_px);
  Figure& set_legend(LegendPosition position);
  Figure& set_max_points_per_series(std::size_t n);
  Axis& x_axis() noexcept { return x_; }
  Axis& y_axis() noexcept { return y_; }

  // Adds a series; the reference stays valid until the next add().
  Series& add(Series series);
  Series& add_line(std::string label, std::vector<double> x, std::vector<double> y);
  Series& add_scatter(std::string label, std::vector<double> x, std::vector<double> y);
  Reference& add_vertical(double x, std::string label = {});
  Reference& add_horizontal(double y, std::string label = {});

  std::string svg() const;
  // Throws std::runtime_error "FILE: cannot write ..." on failure.
  void write(const std::filesystem::path& file) const;

 private:
  std::string title_, subtitle_;
  int width_ = 800;
  int height_ = 480;
  LegendPosition legend_ = LegendPosition::top_right;
  std::size_t max_points_ = 4000;
  Axis x_, y_;
  std::vector<Series> series_;
  std::vector<Reference> vertical_, horizontal_;
};

// About `target` "nice" tick values (steps of 1, 2, 2.5 or 5 x 10^k) within
// [lo, hi]. Empty if the range is not finite or empty.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);
// A tick label with as many decimals as the step needs ("0.25", "1500", "1e+06").
std::string format_tick(double value, double step);

// The default palette (colour-blind-safe, Okabe-Ito).
const std::vector<std::string>& palette();

}  // namespace smc::plot
