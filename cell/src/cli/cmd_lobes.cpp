// smc-cell lobes: the stability-lobe diagram of a milling model by the
// semi-discretization method (smc_machining, lobes.hpp), with critical depths
// found by time-domain simulation (the paper's method, tds.hpp) at a few
// speeds on top. Writes the lobes and the time-domain points as CSV and both
// as one SVG plot. Without --model it uses the paper's case.
//
// Exit codes: 0 ok, 2 bad model file or flags, 3 cannot write an output.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "model_file.hpp"
#include "registry.hpp"
#include "smc/common/csv.hpp"
#include "smc/common/svg_plot.hpp"
#include "smc/machining/lobes.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/paper_case.hpp"
#include "smc/machining/tds.hpp"

namespace {

using smc::cell::cli::Failure;
namespace mc = smc::machining;

struct LobesArgs {
  std::string model_file;
  double rpm_min = 0;
  double rpm_max = 0;
  int speeds = 200;
  double feed_per_tooth_mm = 0;
  std::vector<double> tds_speeds;
  int tds_points = 5;
  double max_depth_mm = 20;
  std::string csv = "lobes.csv";
  std::string tds_csv = "lobes_tds.csv";
  std::string svg = "lobes.svg";
};

void positive(const char* flag, double v) {
  if (!(std::isfinite(v) && v > 0)) {
    throw Failure(2, std::string(flag) + ": must be > 0, got " + std::to_string(v));
  }
}

void run(const LobesArgs& a) {
  const mc::MillingModel model = smc::cell::cli::load_model_or_paper_case(a.model_file);
  const double ref_rpm = model.reference_cut ? model.reference_cut->spindle_rpm : 0;
  double rpm_min = a.rpm_min > 0 ? a.rpm_min : 0.5 * ref_rpm;
  double rpm_max = a.rpm_max > 0 ? a.rpm_max : 2.0 * ref_rpm;
  if (!(rpm_min > 0) || !(rpm_max > 0)) {
    throw Failure(2,
                  "--rpm-min/--rpm-max: the model has no reference_cut.spindle_rpm to derive a "
                  "range from: give both (e.g. --rpm-min 750 --rpm-max 3000)");
  }
  if (rpm_max < rpm_min) throw Failure(2, "--rpm-max: must be >= --rpm-min");
  double feed = a.feed_per_tooth_mm;
  if (!(feed > 0) && model.reference_cut) {
    feed = mc::feed_per_tooth_mm(model.reference_cut->feedrate_mm_s,
                                 model.reference_cut->spindle_rpm, model.cutter.teeth);
  }
  if (!(feed > 0)) {
    throw Failure(2,
                  "--feed-per-tooth: the model has no reference_cut feedrate to derive it "
                  "from: give it (mm/tooth, e.g. 0.1)");
  }
  if (a.speeds < 1) throw Failure(2, "--speeds: must be >= 1");
  positive("--max-depth", a.max_depth_mm);

  std::printf("model %s: %d teeth, radius %g mm, part %g mm wide at offset %g mm\n",
              model.name.c_str(), model.cutter.teeth, model.cutter.radius_mm,
              model.workpiece.width_mm, model.workpiece.offset_mm);
  std::printf("lobes by semi-discretization: %d speeds, %g-%g rpm, %g mm/tooth\n", a.speeds,
              rpm_min, rpm_max, feed);
  std::fflush(stdout);

  mc::LobeOptions lo;
  lo.rpm_min = rpm_min;
  lo.rpm_max = rpm_max;
  lo.speeds = a.speeds;
  lo.feed_per_tooth_mm = feed;
  lo.sdm.max_depth_mm = a.max_depth_mm;
  int last_pct = -1;
  lo.on_progress = [&last_pct](int done, int total) {
    const int pct = done * 100 / total;
    if (pct / 10 != last_pct / 10) {
      std::printf("  %3d%%\n", pct);
      std::fflush(stdout);
      last_pct = pct;
    }
  };
  std::vector<mc::LobePoint> lobes;
  try {
    lobes = mc::stability_lobes(model, lo);
  } catch (const std::invalid_argument& e) {
    throw Failure(2, e.what());
  }

  // Time-domain points.
  std::vector<double> tds_rpm = a.tds_speeds;
  if (tds_rpm.empty() && a.tds_points > 0) {
    for (int i = 0; i < a.tds_points; ++i) {
      tds_rpm.push_back(a.tds_points == 1 ? 0.5 * (rpm_min + rpm_max)
                                          : rpm_min + (rpm_max - rpm_min) * i / (a.tds_points - 1));
    }
    if (ref_rpm >= rpm_min && ref_rpm <= rpm_max) tds_rpm.push_back(ref_rpm);
    std::sort(tds_rpm.begin(), tds_rpm.end());
    tds_rpm.erase(std::unique(tds_rpm.begin(), tds_rpm.end(),
                              [](double p, double q) { return std::abs(p - q) < 1e-6 * q; }),
                  tds_rpm.end());
  }
  std::vector<double> tds_depth, tds_sdm;
  for (const double rpm : tds_rpm) {
    positive("--tds-speeds", rpm);
    mc::TdsSearchOptions to;
    to.max_depth_mm = a.max_depth_mm;
    // Start the search near the lobes' value at that speed.
    const auto near =
        std::min_element(lobes.begin(), lobes.end(), [rpm](const auto& p, const auto& q) {
          return std::abs(p.spindle_rpm - rpm) < std::abs(q.spindle_rpm - rpm);
        });
    if (near != lobes.end() && near->kind != mc::BoundaryKind::none) {
      to.initial_depth_mm = near->critical_depth_mm;
    }
    const mc::TdsSearchResult r = mc::critical_depth_tds(model, rpm, feed, to);
    const mc::LobePoint s = mc::critical_depth_sdm(model, rpm, feed, lo.sdm);
    tds_depth.push_back(r.critical_depth_mm);
    tds_sdm.push_back(s.critical_depth_mm);
    std::printf(
        "time domain at %7.1f rpm: critical depth %.3f mm (%zu runs%s); "
        "semi-discretization %.3f mm\n",
        rpm, r.critical_depth_mm, r.probes.size(), r.bounded ? "" : ", not bounded",
        s.critical_depth_mm);
    std::fflush(stdout);
  }

  // Files.
  std::vector<double> rpm, depth, freq;
  try {
    smc::csv::Writer w(a.csv, {"spindle_rpm", "critical_depth_mm", "kind",
                               "base_chatter_frequency_hz", "intervals"});
    for (const mc::LobePoint& p : lobes) {
      w.field(p.spindle_rpm)
          .field(p.kind == mc::BoundaryKind::none ? std::nan("") : p.critical_depth_mm)
          .field(mc::to_string(p.kind))
          .field(p.base_chatter_frequency_hz)
          .field(static_cast<long long>(p.intervals));
      w.end_row();
      rpm.push_back(p.spindle_rpm);
      depth.push_back(p.kind == mc::BoundaryKind::none ? std::nan("") : p.critical_depth_mm);
    }
    w.close();
    smc::csv::write_columns(a.tds_csv,
                            {"spindle_rpm", "tds_critical_depth_mm", "sdm_critical_depth_mm"},
                            {&tds_rpm, &tds_depth, &tds_sdm});

    smc::plot::Figure fig(model.name + ": stability lobes at " + std::to_string(feed).substr(0, 5) +
                          " mm/tooth");
    fig.x_axis().label = "spindle speed (rpm)";
    fig.y_axis().label = "critical depth of cut (mm)";
    fig.y_axis().include_zero = true;
    fig.add_line("semi-discretization", rpm, depth);
    auto& pts = fig.add_scatter("time-domain simulation", tds_rpm, tds_depth);
    pts.marker = smc::plot::Marker::diamond;
    pts.marker_size = 5;
    if (model.reference_cut) {
      if (ref_rpm >= rpm_min && ref_rpm <= rpm_max) {
        char label[64];
        std::snprintf(label, sizeof label, "%g rpm", ref_rpm);
        fig.add_vertical(ref_rpm, label);
      }
      char label[64];
      std::snprintf(label, sizeof label, "reference depth %g mm", model.reference_cut->depth_mm);
      fig.add_horizontal(model.reference_cut->depth_mm, label);
    }
    fig.set_legend(smc::plot::LegendPosition::top_left);
    fig.write(a.svg);
  } catch (const Failure&) {
    throw;
  } catch (const std::exception& e) {
    throw Failure(3, e.what());
  }
  std::printf("wrote %s, %s, %s\n", a.csv.c_str(), a.tds_csv.c_str(), a.svg.c_str());
}

}  // namespace

SMC_CELL_COMMAND(lobes, 20) {
  auto args = std::make_shared<LobesArgs>();
  auto* sub = app.add_subcommand(
      "lobes",
      "Stability lobes of a milling model (semi-discretization) with time-domain critical "
      "depths on top; writes CSV and SVG. Without --model: the paper's case");
  sub->add_option("-m,--model", args->model_file,
                  "smc.config.MillingModel document (.textproto, or .json); default: the "
                  "paper's case (cell/models/paper_face_mill.textproto)");
  sub->add_option("--rpm-min", args->rpm_min,
                  "Lowest spindle speed (rpm); default: half the model's reference speed");
  sub->add_option("--rpm-max", args->rpm_max,
                  "Highest spindle speed (rpm); default: twice the model's reference speed");
  sub->add_option("--speeds", args->speeds, "Number of speeds (default 200)");
  sub->add_option("--feed-per-tooth", args->feed_per_tooth_mm,
                  "Nominal feed (mm/tooth) for the tangent cutting stiffness; default: from "
                  "the model's reference cut");
  sub->add_option("--tds-speeds", args->tds_speeds,
                  "Speeds (rpm) for time-domain critical depths (default: --tds-points evenly "
                  "spaced plus the reference speed)")
      ->delimiter(',');
  sub->add_option("--tds-points", args->tds_points,
                  "Number of evenly spaced time-domain points (default 5; 0: none)");
  sub->add_option("--max-depth", args->max_depth_mm, "Deepest depth searched (mm, default 20)");
  sub->add_option("--csv", args->csv, "Lobes CSV (default lobes.csv)");
  sub->add_option("--tds-csv", args->tds_csv, "Time-domain points CSV (default lobes_tds.csv)");
  sub->add_option("--svg", args->svg, "Plot (default lobes.svg)");
  sub->callback([args] { run(*args); });
}
