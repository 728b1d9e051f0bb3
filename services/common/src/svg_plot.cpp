#include "smc/common/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace smc::plot {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

struct Range {
  double lo = kInf;
  double hi = -kInf;
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo <= hi; }
};

// The axis range: explicit bounds win; otherwise the data's, padded.
void resolve(const Axis& axis, Range data, double pad_fraction, double& lo, double& hi) {
  if (axis.include_zero) data.add(0.0);
  if (!data.valid()) {
    data.lo = 0;
    data.hi = 1;
  }
  if (data.hi - data.lo <= 0) {
    const double d = data.lo == 0 ? 1.0 : std::abs(data.lo) * 0.1;
    data.lo -= d;
    data.hi += d;
  }
  const double pad = (data.hi - data.lo) * pad_fraction;
  lo = axis.min ? *axis.min : data.lo - (axis.include_zero && data.lo == 0 ? 0 : pad);
  hi = axis.max ? *axis.max : data.hi + (axis.include_zero && data.hi == 0 ? 0 : pad);
  if (!(hi > lo)) hi = lo + 1;
}

double tick_step(double lo, double hi, int target) {
  const double raw = (hi - lo) / std::max(target, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * mag >= raw) return m * mag;
  }
  return 10 * mag;
}

// Keeps, per pixel column, the first, lowest, highest and last points (in
// order), when x is non-decreasing; otherwise everything.
std::vector<std::size_t> thin(const Series& s, double x_lo, double x_hi, double width_px,
                              std::size_t max_points) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  std::vector<std::size_t> keep;
  bool monotonic = true;
  for (std::size_t i = 1; i < n && monotonic; ++i) {
    if (std::isfinite(s.x[i]) && std::isfinite(s.x[i - 1]) && s.x[i] < s.x[i - 1]) {
      monotonic = false;
    }
  }
  if (n <= max_points || !monotonic || s.style != Style::line) {
    keep.resize(n);
    for (std::size_t i = 0; i < n; ++i) keep[i] = i;
    return keep;
  }
  const auto columns =
      static_cast<long>(std::max(1.0, std::min(width_px, static_cast<double>(max_points) / 4.0)));
  long current = std::numeric_limits<long>::min();
  std::size_t first = 0, lowest = 0, highest = 0, last = 0;
  bool open = false;
  const auto flush = [&] {
    if (!open) return;
    std::size_t idx[4] = {first, lowest, highest, last};
    std::sort(idx, idx + 4);
    for (int k = 0; k < 4; ++k) {
      if (keep.empty() || keep.back() != idx[k]) keep.push_back(idx[k]);
    }
    open = false;
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
      flush();
      keep.push_back(i);  // keeps the gap
      continue;
    }
    const long col = static_cast<long>(
        std::floor((s.x[i] - x_lo) / (x_hi - x_lo) * static_cast<double>(columns)));
    if (!open || col != current) {
      flush();
      current = col;
      first = lowest = highest = last = i;
      open = true;
    } else {
      last = i;
      if (s.y[i] < s.y[lowest]) lowest = i;
      if (s.y[i] > s.y[highest]) highest = i;
    }
  }
  flush();
  return keep;
}

void marker_svg(std::ostringstream& o, Marker m, double x, double y, double r,
                const std::string& color, bool filled) {
  const std::string paint = filled ? "fill=\"" + color + "\" stroke=\"" + color + "\""
                                   : "fill=\"white\" stroke=\"" + color + "\"";
  switch (m) {
    case Marker::circle:
      o << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << num(r) << "\" "
        << paint << "/>\n";
      break;
    case Marker::square:
      o << "<rect x=\"" << num(x - r) << "\" y=\"" << num(y - r) << "\" width=\"" << num(2 * r)
        << "\" height=\"" << num(2 * r) << "\" " << paint << "/>\n";
      break;
    case Marker::triangle:
      o << "<polygon points=\"" << num(x) << "," << num(y - 1.2 * r) << " " << num(x - r) << ","
        << num(y + 0.8 * r) << " " << num(x + r) << "," << num(y + 0.8 * r) << "\" " << paint
        << "/>\n";
      break;
    case Marker::diamond:
      o << "<polygon points=\"" << num(x) << "," << num(y - 1.3 * r) << " " << num(x + r) << ","
        << num(y) << " " << num(x) << "," << num(y + 1.3 * r) << " " << num(x - r) << "," << num(y)
        << "\" " << paint << "/>\n";
      break;
    case Marker::cross:
      o << "<path d=\"M" << num(x - r) << "," << num(y - r) << "L" << num(x + r) << ","
        << num(y + r) << "M" << num(x - r) << "," << num(y + r) << "L" << num(x + r) << ","
        << num(y - r) << "\" stroke=\"" << color << "\" stroke-width=\"1.5\" fill=\"none\"/>\n";
      break;
  }
}

}  // namespace

const std::vector<std::string>& palette() {
  static const std::vector<std::string> colors = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                  "#E69F00", "#56B4E9", "#000000", "#F0E442"};
  return colors;
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) return ticks;
  const double step = tick_step(lo, hi, target);
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (int i = 0; i < 1000; ++i) {
    const double v = first + i * step;
    if (v > hi + step * 1e-9) break;
    ticks.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  }
  return ticks;
}

std::string format_tick(double value, double step) {
  char buf[32];
  const double mag = std::max(std::abs(value), std::abs(step));
  if (mag >= 1e6 || (step > 0 && step < 1e-4)) {
    std::snprintf(buf, sizeof buf, "%g", value);
    return buf;
  }
  int decimals = 0;
  if (step > 0) {
    decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    // 2.5 x 10^k needs one more decimal.
    const double lead = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    if (std::abs(lead - 2.5) < 1e-6) ++decimals;
  }
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

Figure::Figure(std::string title) : title_(std::move(title)) {}

Figure& Figure::set_title(std::string title) {
  title_ = std::move(title);
  return *this;
}
Figure& Figure::set_subtitle(std::string subtitle) {
  subtitle_ = std::move(subtitle);
  return *this;
}
Figure& Figure::set_size(int width_px, int height_px) {
  width_ = std::max(width_px, 200);
  height_ = std::max(height_px, 150);
  return *this;
}
Figure& Figure::set_legend(LegendPosition position) {
  legend_ = position;
  return *this;
}
Figure& Figure::set_max_points_per_series(std::size_t n) {
  max_points_ = std::max<std::size_t>(n, 16);
  return *this;
}

Series& Figure::add(Series series) {
  if (series.color.empty()) {
    series.color = palette()[series_.size() % palette().size()];
  }
  series_.push_back(std::move(series));
  return series_.back();
}

Series& Figure::add_line(std::string label, std::vector<double> x, std::vector<double> y) {
  Series s;
  s.label = std::move(label);
  s.x = std::move(x);
  s.y = std::move(y);
  s.style = Style::line;
  return add(std::move(s));
}

Series& Figure::add_scatter(std::string label, std::vector<double> x, std::vector<double> y) {
  Series s;
  s.label = std::move(label);
  s.x = std::move(x);
  s.y = std::move(y);
  s.style = Style::markers;
  return add(std::move(s));
}

Reference& Figure::add_vertical(double x, std::string label) {
  vertical_.push_back(Reference{x, std::move(label)});
  return vertical_.back();
}

Reference& Figure::add_horizontal(double y, std::string label) {
  horizontal_.push_back(Reference{y, std::move(label)});
  return horizontal_.back();
}

std::string Figure::svg() const {
  // Data ranges.
  Range xr, yr;
  for (const Series& s : series_) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        xr.add(s.x[i]);
        yr.add(s.y[i]);
      }
    }
  }
  for (const Reference& r : vertical_) xr.add(r.value);
  for (const Reference& r : horizontal_) yr.add(r.value);
  double x_lo, x_hi, y_lo, y_hi;
  resolve(x_, xr, 0.0, x_lo, x_hi);
  resolve(y_, yr, 0.05, y_lo, y_hi);

  const double left = 72, right = 24, bottom = 56;
  const double top = (title_.empty() ? 20 : 40) + (subtitle_.empty() ? 0 : 18);
  const double pw = width_ - left - right;
  const double ph = height_ - top - bottom;
  const auto px = [&](double x) { return left + (x - x_lo) / (x_hi - x_lo) * pw; };
  const auto py = [&](double y) { return top + (y_hi - y) / (y_hi - y_lo) * ph; };

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width_ << "\" height=\"" << height_
    << "\" viewBox=\"0 0 " << width_ << " " << height_
    << "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<defs><clipPath id=\"plot-area\"><rect x=\"" << num(left) << "\" y=\"" << num(top)
    << "\" width=\"" << num(pw) << "\" height=\"" << num(ph) << "\"/></clipPath></defs>\n";
  if (!title_.empty()) {
    o << "<text x=\"" << num(width_ / 2.0) << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">"
      << escape(title_) << "</text>\n";
  }
  if (!subtitle_.empty()) {
    o << "<text x=\"" << num(width_ / 2.0) << "\" y=\"" << (title_.empty() ? 24 : 44)
      << "\" text-anchor=\"middle\" font-size=\"12\" fill=\"#555555\">" << escape(subtitle_)
      << "</text>\n";
  }

  // Grid and ticks.
  const std::vector<double> xt = nice_ticks(x_lo, x_hi, x_.tick_target);
  const std::vector<double> yt = nice_ticks(y_lo, y_hi, y_.tick_target);
  const double xs = xt.size() > 1 ? xt[1] - xt[0] : tick_step(x_lo, x_hi, x_.tick_target);
  const double ys = yt.size() > 1 ? yt[1] - yt[0] : tick_step(y_lo, y_hi, y_.tick_target);
  o << "<g stroke=\"#e5e5e5\" stroke-width=\"1\">\n";
  for (const double v : xt) {
    o << "<line x1=\"" << num(px(v)) << "\" y1=\"" << num(top) << "\" x2=\"" << num(px(v))
      << "\" y2=\"" << num(top + ph) << "\"/>\n";
  }
  for (const double v : yt) {
    o << "<line x1=\"" << num(left) << "\" y1=\"" << num(py(v)) << "\" x2=\"" << num(left + pw)
      << "\" y2=\"" << num(py(v)) << "\"/>\n";
  }
  o << "</g>\n";
  o << "<rect x=\"" << num(left) << "\" y=\"" << num(top) << "\" width=\"" << num(pw)
    << "\" height=\"" << num(ph) << "\" fill=\"none\" stroke=\"#333333\"/>\n";
  o << "<g fill=\"#333333\">\n";
  for (const double v : xt) {
    o << "<line x1=\"" << num(px(v)) << "\" y1=\"" << num(top + ph) << "\" x2=\"" << num(px(v))
      << "\" y2=\"" << num(top + ph + 5) << "\" stroke=\"#333333\"/>\n";
    o << "<text x=\"" << num(px(v)) << "\" y=\"" << num(top + ph + 18)
      << "\" text-anchor=\"middle\">" << escape(format_tick(v, xs)) << "</text>\n";
  }
  for (const double v : yt) {
    o << "<line x1=\"" << num(left - 5) << "\" y1=\"" << num(py(v)) << "\" x2=\"" << num(left)
      << "\" y2=\"" << num(py(v)) << "\" stroke=\"#333333\"/>\n";
    o << "<text x=\"" << num(left - 8) << "\" y=\"" << num(py(v) + 4) << "\" text-anchor=\"end\">"
      << escape(format_tick(v, ys)) << "</text>\n";
  }
  o << "</g>\n";
  if (!x_.label.empty()) {
    o << "<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(height_ - 12.0)
      << "\" text-anchor=\"middle\" font-size=\"13\">" << escape(x_.label) << "</text>\n";
  }
  if (!y_.label.empty()) {
    o << "<text transform=\"translate(16," << num(top + ph / 2)
      << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"13\">" << escape(y_.label)
      << "</text>\n";
  }

  // Reference lines.
  o << "<g clip-path=\"url(#plot-area)\">\n";
  for (const Reference& r : vertical_) {
    if (!std::isfinite(r.value)) continue;
    o << "<line x1=\"" << num(px(r.value)) << "\" y1=\"" << num(top) << "\" x2=\""
      << num(px(r.value)) << "\" y2=\"" << num(top + ph) << "\" stroke=\"" << r.color
      << "\" stroke-width=\"" << num(r.line_width) << "\""
      << (r.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
  }
  for (const Reference& r : horizontal_) {
    if (!std::isfinite(r.value)) continue;
    o << "<line x1=\"" << num(left) << "\" y1=\"" << num(py(r.value)) << "\" x2=\""
      << num(left + pw) << "\" y2=\"" << num(py(r.value)) << "\" stroke=\"" << r.color
      << "\" stroke-width=\"" << num(r.line_width) << "\""
      << (r.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
  }

  // Series.
  for (const Series& s : series_) {
    const std::vector<std::size_t> idx = thin(s, x_lo, x_hi, pw, max_points_);
    if (s.style != Style::markers) {
      std::string points;
      const auto emit = [&] {
        if (points.empty()) return;
        o << "<polyline fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\""
          << num(s.line_width) << "\" stroke-linejoin=\"round\""
          << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << " points=\"" << points << "\"/>\n";
        points.clear();
      };
      for (const std::size_t i : idx) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
          emit();
          continue;
        }
        if (!points.empty()) points += ' ';
        points += num(px(s.x[i])) + "," + num(py(s.y[i]));
      }
      emit();
    }
    if (s.style != Style::line) {
      for (const std::size_t i : idx) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
        marker_svg(o, s.marker, px(s.x[i]), py(s.y[i]), s.marker_size, s.color, s.filled);
      }
    }
  }
  o << "</g>\n";

  // Reference labels (unclipped, inside the plot edge).
  for (const Reference& r : vertical_) {
    if (!std::isfinite(r.value) || r.label.empty()) continue;
    if (r.value < x_lo || r.value > x_hi) continue;
    o << "<text x=\"" << num(px(r.value) + 4) << "\" y=\"" << num(top + 14)
      << "\" font-size=\"11\" fill=\"" << r.color << "\">" << escape(r.label) << "</text>\n";
  }
  for (const Reference& r : horizontal_) {
    if (!std::isfinite(r.value) || r.label.empty()) continue;
    if (r.value < y_lo || r.value > y_hi) continue;
    o << "<text x=\"" << num(left + pw - 4) << "\" y=\"" << num(py(r.value) - 4)
      << "\" text-anchor=\"end\" font-size=\"11\" fill=\"" << r.color << "\">" << escape(r.label)
      << "</text>\n";
  }

  // Legend.
  std::vector<const Series*> entries;
  for (const Series& s : series_) {
    if (!s.label.empty()) entries.push_back(&s);
  }
  if (legend_ != LegendPosition::none && !entries.empty()) {
    std::size_t longest = 0;
    for (const Series* s : entries) longest = std::max(longest, s->label.size());
    const double lw = 40 + 6.5 * static_cast<double>(longest);
    const double lh = 8 + 18 * static_cast<double>(entries.size());
    const bool at_right =
        legend_ == LegendPosition::top_right || legend_ == LegendPosition::bottom_right;
    const bool at_top = legend_ == LegendPosition::top_right || legend_ == LegendPosition::top_left;
    const double lx = at_right ? left + pw - lw - 8 : left + 8;
    const double ly = at_top ? top + 8 : top + ph - lh - 8;
    o << "<rect x=\"" << num(lx) << "\" y=\"" << num(ly) << "\" width=\"" << num(lw)
      << "\" height=\"" << num(lh)
      << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#999999\"/>\n";
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const Series& s = *entries[k];
      const double ey = ly + 4 + 18 * static_cast<double>(k) + 9;
      if (s.style != Style::markers) {
        o << "<line x1=\"" << num(lx + 6) << "\" y1=\"" << num(ey) << "\" x2=\"" << num(lx + 30)
          << "\" y2=\"" << num(ey) << "\" stroke=\"" << s.color << "\" stroke-width=\""
          << num(s.line_width) << "\"" << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
      }
      if (s.style != Style::line) {
        marker_svg(o, s.marker, lx + 18, ey, s.marker_size, s.color, s.filled);
      }
      o << "<text x=\"" << num(lx + 36) << "\" y=\"" << num(ey + 4) << "\">" << escape(s.label)
        << "</text>\n";
    }
  }
  o << "</svg>\n";
  return o.str();
}

void Figure::write(const std::filesystem::path& file) const {
  const std::string text = svg();
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  out << text;
  out.close();
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

}  // namespace smc::plot
