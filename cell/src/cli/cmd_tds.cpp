// smc-cell tds: one cut simulated in the time domain (smc_machining,
// tds.hpp); writes its force history as CSV and SVG and says whether it
// chatters. Without --model it uses the paper's case at its reference cut
// (2 mm at 1500 rpm and 10 mm/s).
//
// Exit codes: 0 ok, 2 bad model file or flags, 3 cannot write an output.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "model_file.hpp"
#include "registry.hpp"
#include "smc/common/csv.hpp"
#include "smc/common/svg_plot.hpp"
#include "smc/machining/cutting.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/paper_case.hpp"
#include "smc/machining/tds.hpp"

namespace {

using smc::cell::cli::Failure;
namespace mc = smc::machining;

struct TdsArgs {
  std::string model_file;
  double rpm = 0;
  double feedrate_mm_s = 0;
  double feed_per_tooth_mm = 0;
  double depth_mm = -1;
  double duration_s = 0;
  double step_s = 0;
  bool pass = false;
  std::string csv = "tds.csv";
  std::string svg = "tds.svg";
};

void run(const TdsArgs& a) {
  const mc::MillingModel model = smc::cell::cli::load_model_or_paper_case(a.model_file);
  const auto& ref = model.reference_cut;
  const double rpm = a.rpm > 0 ? a.rpm : (ref ? ref->spindle_rpm : 0);
  if (!(rpm > 0)) {
    throw Failure(2, "--rpm: the model has no reference_cut.spindle_rpm: give the spindle speed");
  }
  if (a.feedrate_mm_s > 0 && a.feed_per_tooth_mm > 0) {
    throw Failure(2, "--feedrate and --feed-per-tooth: give one of them, not both");
  }
  double feed = a.feed_per_tooth_mm;
  if (!(feed > 0)) {
    const double feedrate = a.feedrate_mm_s > 0 ? a.feedrate_mm_s : (ref ? ref->feedrate_mm_s : 0);
    feed = mc::feed_per_tooth_mm(feedrate, rpm, model.cutter.teeth);
  }
  if (!(feed > 0)) {
    throw Failure(2,
                  "--feedrate: the model has no reference_cut.feedrate_mm_s: give --feedrate "
                  "(mm/s) or --feed-per-tooth (mm)");
  }
  const double depth = a.depth_mm >= 0 ? a.depth_mm : (ref ? ref->depth_mm : -1);
  if (!(depth > 0)) {
    throw Failure(2, "--depth: the model has no reference_cut.depth_mm: give the depth (mm)");
  }
  const double feedrate = feed * model.cutter.teeth * rpm / 60.0;

  mc::BatchOptions o;
  o.steady = !a.pass;
  o.max_internal_step_s = a.step_s;
  o.record_every_s = 0.5e-3;
  if (a.pass) {
    // From 5 mm before the part until the cutter has left it.
    o.start_position_mm = -model.cutter.radius_mm - 5;
    o.duration_s = a.duration_s > 0
                       ? a.duration_s
                       : (model.workpiece.length_mm + 2 * model.cutter.radius_mm + 10) / feedrate;
  } else {
    o.duration_s = a.duration_s > 0 ? a.duration_s : 0.5;
  }
  std::printf("model %s: %g rpm, %g mm/tooth (%g mm/s), depth %g mm, %g s%s\n", model.name.c_str(),
              rpm, feed, feedrate, depth, o.duration_s,
              a.pass ? ", one pass along the part" : ", steady cut");
  std::fflush(stdout);
  mc::BatchResult r;
  try {
    r = mc::simulate(model, mc::CutConditions{rpm, feed, depth}, o);
  } catch (const std::invalid_argument& e) {
    throw Failure(2, e.what());
  }
  double max_power = 0;
  for (const double p : r.power_w) max_power = std::max(max_power, p);
  std::printf(
      "internal step %.3g s (%d per tooth period); max |F_y| %.1f N; mean power %.1f W, "
      "peak %.1f W\n",
      r.internal_step_s, r.steps_per_tooth_period, r.max_abs_fy_n, r.mean_power_w, max_power);
  std::printf("%s: %s\n", r.stability.verdict == mc::Verdict::stable ? "stable" : "CHATTER",
              r.stability.reason.c_str());
  if (o.steady) {
    const mc::StabilityReport s =
        mc::assess_stability(model, mc::CutConditions{rpm, feed, depth}, 160, a.step_s);
    std::printf("stability of the steady cut (disturbance test): %s\n", s.reason.c_str());
  }

  try {
    std::vector<double> teeth(r.teeth_in_cut.begin(), r.teeth_in_cut.end());
    smc::csv::write_columns(
        a.csv,
        {"time_s", "fx_n", "fy_n", "fz_n", "power_w", "tool_x_mm", "tool_y_mm", "part_x_mm",
         "part_y_mm", "tool_position_mm", "teeth_in_cut"},
        {&r.time_s, &r.fx_n, &r.fy_n, &r.fz_n, &r.power_w, &r.tool_x_mm, &r.tool_y_mm, &r.part_x_mm,
         &r.part_y_mm, &r.tool_position_mm, &teeth});
    char title[200];
    std::snprintf(title, sizeof title, "%s: %g mm at %g rpm, %g mm/tooth (%s)", model.name.c_str(),
                  depth, rpm, feed,
                  r.stability.verdict == mc::Verdict::stable ? "stable" : "chatter");
    smc::plot::Figure fig(title);
    fig.x_axis().label = "time (s)";
    fig.y_axis().label = "force on the tool (N)";
    fig.add_line("F_x", r.time_s, r.fx_n);
    fig.add_line("F_y", r.time_s, r.fy_n);
    fig.add_line("F_z", r.time_s, r.fz_n);
    fig.add_horizontal(0.0).dashed = false;
    fig.write(a.svg);
  } catch (const std::exception& e) {
    throw Failure(3, e.what());
  }
  std::printf("wrote %s, %s\n", a.csv.c_str(), a.svg.c_str());
}

}  // namespace

SMC_CELL_COMMAND(tds, 21) {
  auto args = std::make_shared<TdsArgs>();
  auto* sub = app.add_subcommand(
      "tds",
      "Simulate one cut in the time domain; write its force history (CSV, SVG) and say "
      "whether it chatters. Without --model: the paper's case at its reference cut");
  sub->add_option("-m,--model", args->model_file,
                  "smc.config.MillingModel document (.textproto, or .json); default: the "
                  "paper's case (cell/models/paper_face_mill.textproto)");
  sub->add_option("--rpm", args->rpm, "Spindle speed (rpm); default: the reference cut's");
  sub->add_option("--feedrate", args->feedrate_mm_s,
                  "Feedrate (mm/s); default: the reference cut's");
  sub->add_option("--feed-per-tooth", args->feed_per_tooth_mm,
                  "Feed per tooth (mm), instead of --feedrate");
  sub->add_option("--depth", args->depth_mm, "Depth of cut (mm); default: the reference cut's");
  sub->add_option("--duration", args->duration_s,
                  "Simulated time (s); default 0.5, or the whole pass with --pass");
  sub->add_option("--step", args->step_s, "Internal step bound (s); default: the model's (1e-5 s)");
  sub->add_flag("--pass", args->pass,
                "Travel along the part from 5 mm before it (entry, steady cut, exit) instead "
                "of a steady cut from the start");
  sub->add_option("--csv", args->csv, "Force history CSV (default tds.csv)");
  sub->add_option("--svg", args->svg, "Force plot (default tds.svg)");
  sub->callback([args] { run(*args); });
}
