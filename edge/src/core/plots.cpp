#include "plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "smc/common/svg_plot.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace {

const char* variant_name(int v) {
  switch (v) {
    case smc::config::SMC_NONE:
      return "no process control";
    case smc::config::SMC_I:
      return "SMC I";
    case smc::config::SMC_II:
      return "SMC II";
    case smc::config::SMC_II_PLUS:
      return "SMC II+";
    default:
      return "unspecified";
  }
}

// Pass starts, feed holds, chatter and rewrites as vertical lines. Labels
// closer than `min_gap` (machine seconds) to the previous label are left off
// so that they do not print over each other; the line is still drawn.
void add_marks(plot::Figure& fig, const RunResult& run, double min_gap) {
  struct Mark {
    double t;
    std::string label;
    const char* color;
    int priority;  // lower places its label first
  };
  std::vector<Mark> marks;
  for (size_t i = 0; i < run.events.size(); ++i) {
    const EdgeEvent& e = run.events[i];
    char label[64];
    switch (e.kind) {
      case EventKind::kPassStarted:
        std::snprintf(label, sizeof label, "pass %d/%d", e.pass_index + 1, e.pass_count);
        marks.push_back({e.t_s, label, "#999999", 2});
        break;
      case EventKind::kChatterDetected:
      case EventKind::kChatterSignalled: {
        std::string l = e.kind == EventKind::kChatterDetected ? "chatter" : "chatter (operator)";
        // The rewrite follows within a fast period: one mark says both.
        for (size_t k = i + 1; k < run.events.size() && run.events[k].t_s < e.t_s + 0.2; ++k) {
          if (run.events[k].kind == EventKind::kProgramRewritten) {
            l += ": " + std::to_string(run.events[k].pass_count) + " passes";
          }
        }
        marks.push_back({e.t_s, l, "#D55E00", 0});
        break;
      }
      case EventKind::kFault:
        marks.push_back({e.t_s, std::string("fault: ") + to_string(e.fault), "#000000", 0});
        break;
      default:
        break;
    }
  }
  bool held = false;
  for (const RevolutionRecord& r : run.revolutions) {
    const bool now = (r.active & bit(ModuleId::C)) != 0;
    if (now != held) marks.push_back({r.t_s, now ? "hold" : "release", "#0072B2", 1});
    held = now;
  }
  // Labels by priority (chatter and faults, then holds, then passes), each
  // only where no label is placed within min_gap.
  std::vector<size_t> order(marks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return marks[a].priority < marks[b].priority; });
  std::vector<double> placed;
  std::vector<bool> labelled(marks.size(), false);
  for (size_t i : order) {
    bool room = true;
    for (double t : placed) room = room && std::fabs(marks[i].t - t) >= min_gap;
    if (room) {
      placed.push_back(marks[i].t);
      labelled[i] = true;
    }
  }
  for (size_t i = 0; i < marks.size(); ++i) {
    fig.add_vertical(marks[i].t, labelled[i] ? marks[i].label : std::string()).color =
        marks[i].color;
  }
}

}  // namespace

void write_plots(const std::string& dir, const EdgeCore& core, const RunResult& run,
                 const smc::config::RunSummary& summary) {
  const std::filesystem::path out(dir);
  std::vector<double> t, fy, fref, feed;
  for (const RevolutionRecord& r : run.revolutions) {
    t.push_back(r.t_s);
    fy.push_back(r.f_y_peak_n);
    fref.push_back(r.f_ref_n);
    feed.push_back(r.feedrate_mm_s);
  }
  // About a label's width on a 1000 px wide plot.
  const double gap = (run.end_time_s > 0 ? run.end_time_s : 1.0) / 14.0;
  const std::string name =
      std::string(variant_name(core.config().variant)) + " (" + core.config().config_id + ")";
  {
    char title[200];
    std::snprintf(title, sizeof title,
                  "History of F_Y, %s: overshoot %.0f %%, peak %+.0f %% of F_ref", name.c_str(),
                  summary.overshoot_pct(), summary.peak_force_violation_pct());
    plot::Figure fig(title);
    fig.set_size(1000, 480);
    fig.x_axis().label = "machine time (s)";
    fig.y_axis().label = "F_Y = max |F_y| per revolution (N)";
    fig.y_axis().include_zero = true;
    fig.add_line("F_Y", t, fy);
    auto& ref = fig.add_line("F_ref (power limit)", t, fref);
    ref.dashed = true;
    ref.color = "#009E73";
    add_marks(fig, run, gap);
    fig.write(out / "force.svg");
  }
  {
    plot::Figure fig("Commanded feedrate, " + name);
    fig.set_size(1000, 360);
    fig.x_axis().label = "machine time (s)";
    fig.y_axis().label = "feedrate (mm/s)";
    fig.y_axis().include_zero = true;
    fig.add_line("feedrate", t, feed);
    add_marks(fig, run, gap);
    fig.write(out / "feed.svg");
  }
  {
    // Raw force around the chatter detection, or in the middle of the last pass.
    double t0 = 0, t1 = 0;
    if (summary.chatter_detected_s() >= 0) {
      t0 = summary.chatter_detected_s() - 0.3;
      t1 = summary.chatter_detected_s() + 0.05;
    } else if (summary.passes_size() > 0) {
      const auto& p = summary.passes(summary.passes_size() - 1);
      const double mid = 0.5 * (std::max(p.contact_s(), p.start_s()) + p.end_s());
      t0 = mid - 0.1;
      t1 = mid + 0.1;
    }
    std::vector<double> rt, ry, rz;
    for (const TraceSample& s : run.samples) {
      if (s.t_s < t0 || s.t_s > t1) continue;
      rt.push_back(s.t_s);
      ry.push_back(s.f_y_n);
      rz.push_back(s.f_z_n);
    }
    plot::Figure fig("Raw force samples (0.5 ms, after the anti-alias filters), " + name);
    fig.set_size(1000, 400);
    fig.x_axis().label = "machine time (s)";
    fig.y_axis().label = "force (N)";
    fig.add_line("F_y", rt, ry);
    fig.add_line("F_z", rt, rz);
    if (summary.chatter_detected_s() >= 0)
      fig.add_vertical(summary.chatter_detected_s(), "chatter detected");
    if (summary.chatter_onset_s() >= 0 && summary.chatter_onset_s() >= t0) {
      fig.add_vertical(summary.chatter_onset_s(), "onset");
    }
    fig.write(out / "raw.svg");
  }
}

}  // namespace smc::edge
