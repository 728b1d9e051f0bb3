#include "chatter_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>
#include <system_error>

#include "smc/common/svg_plot.hpp"

namespace smc::bench {

namespace {

using plot::Figure;
using plot::Marker;
using plot::Series;
using plot::Style;

// Each cut's x: its speed, moved a little by width (left to right in the
// order given) and by runout, so that a speed's cuts do not hide each other.
struct Spread {
  std::vector<double> widths, runouts;
  double step = 0;        // rpm between two widths' columns
  double lo = 0, hi = 1;  // the x axis: half a gap beyond the first and last speeds
  double x(double rpm, double width, double runout) const {
    const auto at = [](const std::vector<double>& v, double value) {
      return static_cast<double>(std::lower_bound(v.begin(), v.end(), value) - v.begin());
    };
    const double w = at(widths, width) - 0.5 * static_cast<double>(widths.size() - 1);
    const double r = at(runouts, runout) - 0.5 * static_cast<double>(runouts.size() - 1);
    return rpm + step * w + 0.25 * step * r;
  }
};

Spread spread_of(const std::vector<ChatterStudyFigures::Cut>& cuts) {
  std::set<double> rpms, widths, runouts;
  for (const auto& c : cuts) {
    rpms.insert(c.rpm);
    widths.insert(c.width);
    runouts.insert(c.runout);
  }
  double gap = 1000;
  for (auto it = rpms.begin(); it != rpms.end() && std::next(it) != rpms.end(); ++it) {
    gap = std::min(gap, *std::next(it) - *it);
  }
  Spread s;
  s.widths.assign(widths.begin(), widths.end());
  s.runouts.assign(runouts.begin(), runouts.end());
  s.step = gap / (4.0 * static_cast<double>(std::max<size_t>(widths.size(), 1)));
  if (!rpms.empty()) {
    s.lo = *rpms.begin() - 0.5 * gap;
    s.hi = *rpms.rbegin() + 0.5 * gap;
  }
  return s;
}

std::filesystem::path written(const Figure& fig, std::filesystem::path path) {
  fig.write(path);
  return path;
}

const Marker kRunoutMarkers[] = {Marker::circle, Marker::square, Marker::diamond, Marker::triangle};

std::filesystem::path delay_figure(const std::filesystem::path& dir, const ChatterStudyFigures& f) {
  constexpr double kShown = 10;  // revolutions; later ones are drawn above
  const Spread sp = spread_of(f.cuts);
  int within = 0, detected = 0;
  std::map<double, Series> by_runout;
  Series later, missed, premature;
  later.style = missed.style = premature.style = Style::markers;
  premature.marker = Marker::cross;
  premature.color = "#000000";
  premature.marker_size = 5;
  later.marker = Marker::triangle;
  missed.marker = Marker::cross;
  later.color = "#555555";
  missed.color = "#D55E00";
  double lowest = 0;
  for (const auto& c : f.cuts) {
    if (!c.unstable) continue;
    const double x = sp.x(c.rpm, c.width, c.runout);
    if (c.premature) {
      premature.x.push_back(x);
      premature.y.push_back(c.delay_revs);
      lowest = std::min(lowest, c.delay_revs);
      continue;
    }
    if (!c.detected) {
      missed.x.push_back(x);
      missed.y.push_back(kShown + 1.4);
      continue;
    }
    ++detected;
    if (c.delay_revs <= 3.0) ++within;
    if (c.delay_revs > kShown) {
      later.x.push_back(x);
      later.y.push_back(kShown + 0.7);
      continue;
    }
    Series& s = by_runout[c.runout];
    s.x.push_back(x);
    s.y.push_back(c.delay_revs);
    lowest = std::min(lowest, c.delay_revs);
  }
  char title[200];
  std::snprintf(title, sizeof title,
                "E: %d of %d unstable cuts within 3 revolutions of the onset, %d detected, %d "
                "false detections",
                within, f.unstable, detected, f.e_false);
  Figure fig(title);
  fig.set_subtitle(f.subtitle);
  fig.set_size(960, 540);
  fig.x_axis().label =
      "spindle speed, rpm (at each speed, widths " + joined(sp.widths, " mm") + " left to right)";
  fig.x_axis().min = sp.lo;
  fig.x_axis().max = sp.hi;
  fig.y_axis().label = "revolutions from the onset to E's detection";
  fig.y_axis().min = std::floor(lowest);
  fig.y_axis().max = kShown + 2;
  size_t k = 0;
  for (auto& [runout, s] : by_runout) {
    char label[64];
    std::snprintf(label, sizeof label, "runout %g um", runout);
    s.label = label;
    s.style = Style::markers;
    s.marker = kRunoutMarkers[k % 4];
    s.filled = false;
    s.color = plot::palette()[(k + 1) % plot::palette().size()];
    fig.add(std::move(s));
    ++k;
  }
  char label[64];
  std::snprintf(label, sizeof label, "later than %g revolutions (%zu)", kShown, later.x.size());
  later.label = label;
  std::snprintf(label, sizeof label, "missed (%zu)", missed.x.size());
  missed.label = label;
  if (!later.x.empty()) fig.add(std::move(later));
  if (!missed.x.empty()) fig.add(std::move(missed));
  std::snprintf(label, sizeof label, "before the onset, the mill's q below it: false (%zu)",
                premature.x.size());
  premature.label = label;
  if (!premature.x.empty()) fig.add(std::move(premature));
  fig.add_horizontal(3.0, "the goal: 3 revolutions");
  if (lowest < 0) fig.add_horizontal(0.0, "the label's onset (below: E decided before it)");
  // The legend in the bottom corner with fewer cuts under it (the top has
  // the late and missed ones).
  const double y_lo = std::floor(lowest), y_box = y_lo + 0.35 * (kShown + 2 - y_lo);
  const double x_left = sp.lo + 0.45 * (sp.hi - sp.lo), x_right = sp.hi - 0.45 * (sp.hi - sp.lo);
  int left = 0, right = 0;
  for (const auto& c : f.cuts) {
    if (!c.unstable || !(c.delay_revs < y_box)) continue;
    const double x = sp.x(c.rpm, c.width, c.runout);
    left += x < x_left ? 1 : 0;
    right += x > x_right ? 1 : 0;
  }
  fig.set_legend(left < right ? plot::LegendPosition::bottom_left
                              : plot::LegendPosition::bottom_right);
  return written(fig, dir / "chatter-delay.svg");
}

std::filesystem::path margin_figure(const std::filesystem::path& dir,
                                    const ChatterStudyFigures& f) {
  constexpr double kLo = 0.10, kHi = 0.20;
  const Spread sp = spread_of(f.cuts);
  Series stable, unstable;
  stable.style = unstable.style = Style::markers;
  stable.color = "#0072B2";
  stable.filled = false;
  unstable.color = "#D55E00";
  unstable.marker = Marker::diamond;
  double stable_most = 0, unstable_least = HUGE_VAL;
  int stable_out = 0, unstable_out = 0, flips = 0;
  for (const auto& c : f.cuts) {
    if (c.unstable && c.by_flip) {
      ++flips;
      continue;
    }
    if (c.unstable) {
      unstable_least = std::min(unstable_least, c.level);
    } else {
      stable_most = std::max(stable_most, c.level);
    }
    if (c.level < kLo || c.level > kHi) {
      (c.unstable ? unstable_out : stable_out) += 1;
      continue;
    }
    Series& s = c.unstable ? unstable : stable;
    s.x.push_back(sp.x(c.rpm, c.width, c.runout));
    s.y.push_back(c.level);
  }
  char title[200];
  std::snprintf(title, sizeof title,
                "The label's margin: stable cuts' onset levels up to %.4f, unstable cuts' "
                "from %.4f (the mill's q)",
                stable_most, std::isfinite(unstable_least) ? unstable_least : 0.0);
  Figure fig(title);
  fig.set_subtitle(f.subtitle);
  fig.set_size(960, 540);
  char x_label[300];
  std::snprintf(x_label, sizeof x_label,
                "spindle speed, rpm (widths %s); not drawn: outside %.2f-%.2f %d stable, %d "
                "unstable cuts, and %d period doublings",
                joined(sp.widths, " mm").c_str(), kLo, kHi, stable_out, unstable_out, flips);
  fig.x_axis().label = x_label;
  fig.x_axis().min = sp.lo;
  fig.x_axis().max = sp.hi;
  fig.y_axis().label = "onset level: the mill's q where it rose";
  fig.y_axis().min = kLo;
  fig.y_axis().max = kHi;
  char label[80];
  std::snprintf(label, sizeof label, "stable: the largest level (%zu)", stable.x.size());
  stable.label = label;
  std::snprintf(label, sizeof label, "unstable: the onset's level (%zu)", unstable.x.size());
  unstable.label = label;
  fig.add(std::move(stable));
  fig.add(std::move(unstable));
  fig.add_horizontal(f.onset_q, "the label's threshold");
  fig.set_legend(plot::LegendPosition::bottom_left);
  return written(fig, dir / "chatter-margin.svg");
}

std::filesystem::path estimate_figure(const std::filesystem::path& dir,
                                      const ChatterStudyFigures& f) {
  constexpr double kLo = 0.05, kHi = 0.40;
  constexpr size_t kPerSpeed = 500;
  std::map<double, std::vector<const ChatterStudyFigures::QPair*>> by_speed;
  for (const auto& p : f.q_pairs) {
    if (p.mill_q >= kLo && p.mill_q <= kHi) by_speed[p.rpm].push_back(&p);
  }
  size_t total = 0, drawn = 0;
  Figure fig;
  fig.set_subtitle(f.subtitle);
  fig.set_size(760, 660);
  size_t k = 0;
  for (const auto& [rpm, pairs] : by_speed) {
    Series s;
    char label[32];
    std::snprintf(label, sizeof label, "%g rpm (%zu)", rpm, pairs.size());
    s.label = label;
    s.style = Style::markers;
    s.marker_size = 1.6;
    s.color = plot::palette()[k++ % plot::palette().size()];
    // Every n-th: deterministic, and the same revolutions on every run.
    const size_t stride = (pairs.size() + kPerSpeed - 1) / kPerSpeed;
    for (size_t i = 0; i < pairs.size(); i += std::max<size_t>(stride, 1)) {
      s.x.push_back(pairs[i]->mill_q);
      s.y.push_back(pairs[i]->e_q);
    }
    total += pairs.size();
    drawn += s.x.size();
    fig.add(std::move(s));
  }
  for (const double g : {1.0, 0.9, 1.1}) {
    Series& line =
        fig.add_line(g == 1.0 ? "E reads the mill's q" : "", {kLo, kHi}, {g * kLo, g * kHi});
    line.color = "#333333";
    line.dashed = g != 1.0;
    line.line_width = 1.0;
  }
  char title[160];
  std::snprintf(title, sizeof title,
                "E's q against the mill's, labelling runs' revolutions (%zu of %zu drawn; "
                "dashed: +-10 %%)",
                drawn, total);
  fig.set_title(title);
  fig.x_axis().label = "the mill's own q (0.05-0.40 drawn, higher speeds on top)";
  fig.y_axis().label = "E's q";
  fig.x_axis().min = fig.y_axis().min = kLo;
  fig.x_axis().max = fig.y_axis().max = kHi;
  fig.add_vertical(f.onset_q, "the label's 0.15");
  fig.add_horizontal(f.onset_q);
  fig.set_legend(plot::LegendPosition::top_left);
  return written(fig, dir / "chatter-estimate.svg");
}

std::filesystem::path error_figure(const std::filesystem::path& dir, const ChatterStudyFigures& f) {
  Series false_mean, late_mean, false_range, late_range;
  false_mean.label = "the label's rule: false detections (mean)";
  late_mean.label = "the label's rule: unstable cuts not within 3 revolutions (mean)";
  false_mean.style = late_mean.style = Style::line_and_markers;
  false_mean.color = false_range.color = "#D55E00";
  late_mean.color = late_range.color = "#0072B2";
  late_mean.marker = Marker::square;
  for (const auto& r : f.error_rows) {
    const double x = 100 * r.sigma;
    false_mean.x.push_back(x);
    false_mean.y.push_back(r.false_mean);
    late_mean.x.push_back(x);
    late_mean.y.push_back(r.late_mean);
    // Each range a short vertical stroke; NaN breaks the line between them.
    for (Series* s : {&false_range, &late_range}) {
      const bool is_false = s == &false_range;
      s->x.insert(s->x.end(), {x, x, NAN});
      s->y.insert(s->y.end(), {static_cast<double>(is_false ? r.false_lo : r.late_lo),
                               static_cast<double>(is_false ? r.false_hi : r.late_hi), NAN});
    }
  }
  false_range.line_width = late_range.line_width = 3;
  char title[200];
  std::snprintf(title, sizeof title,
                "How exact a q the goal asks for: the label's own rule on the mill's q read "
                "with an error (%d unstable cuts)",
                f.unstable);
  Figure fig(title);
  fig.set_subtitle(f.subtitle);
  fig.set_size(960, 540);
  fig.x_axis().label =
      "error of the mill's q, % rms, drawn per revolution (bars: fewest to most over the draws)";
  fig.y_axis().label = "cuts";
  fig.y_axis().include_zero = true;
  fig.add(std::move(false_range));
  fig.add(std::move(late_range));
  fig.add(std::move(false_mean));
  fig.add(std::move(late_mean));
  char label[80];
  std::snprintf(label, sizeof label, "E: %d false detections", f.e_false);
  fig.add_horizontal(f.e_false, label).color = "#D55E00";
  std::snprintf(label, sizeof label, "E: %d not within 3 revolutions", f.e_late);
  fig.add_horizontal(f.e_late, label).color = "#0072B2";
  fig.set_legend(plot::LegendPosition::top_left);
  return written(fig, dir / "chatter-error.svg");
}

}  // namespace

std::string joined(const std::vector<double>& values, const char* unit) {
  std::string out;
  char one[32];
  for (size_t i = 0; i < values.size(); ++i) {
    std::snprintf(one, sizeof one, "%s%g", i > 0 ? ", " : "", values[i]);
    out += one;
  }
  return out + unit;
}

std::vector<std::filesystem::path> write_chatter_figures(const std::filesystem::path& dir,
                                                         const ChatterStudyFigures& f) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create the directory: " + ec.message());
  return {delay_figure(dir, f), margin_figure(dir, f), estimate_figure(dir, f),
          error_figure(dir, f)};
}

}  // namespace smc::bench
