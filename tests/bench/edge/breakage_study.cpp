// Module N (tool-breakage detector) under SMC II+ on the simulated mill:
// detection delay of a broken tooth and false detections on intact cutters,
// across spindle speeds, widths of cut, depths, cutter runout and the
// moment of the break (entry, steady cut, exit).
//
//   build/release/bin/smc-bench-breakage [--speeds 750,1100,...] [--widths 25,37,50]
//       [--fractions 0.3,0.6,0.9] [--runouts 0,10,20] [--critical-feed 0.03] [--tooth T]
//       [--timings 0.1,0.5,0.9] [--mill-model FILE] [--seeds N] [--quick] [--verbose]
//
// --help lists every flag with what it does and its default.
//
// For each speed and width the critical depth is found by time-domain
// simulation (smc::machining) at --critical-feed (default 0.03 mm/tooth:
// near the feed the force controller settles at under the power limit; with
// power-law pressures the critical depth falls with the feed, so the
// programmed 0.1 mm/tooth would put the deeper cuts beyond the lobes); the
// depths are the given fractions of it. Each cut runs once with the intact
// cutter -- every revolution N judged counts towards the false-detection
// figure, and the largest score N reached on an immediate decision gives the
// margin -- and once per break timing with tooth T (default 2) losing its
// edge: by default at entry (a tenth of the path in contact), in the steady
// cut (the middle) and at exit (nine tenths). --timings takes other shares
// of the path in contact, or revolutions after the first revolution in
// contact with a trailing r (--timings 0r,1r,2r,3r: the moments N's
// comparison with the revolution before cannot cover; edge/README.md, "What
// N does not see"). The delay is from the break to N's
// detection, in revolutions. "Within a revolution" is on the sample grid:
// by the first sample at which a revolution has passed since the break (at
// 1100 rpm a revolution is 109.1 samples, and the 110th is the first N can
// decide on). Revolutions after E saw chatter are left out
// of the intact count and reported apart, as are breaks after a chatter.
// Breaks N cannot see are counted apart too: of a tooth whose chip (runout
// kinematics, at the feed of the moment) is below the threshold's share of
// the mean chip, or while the mean window force is below N's floor.
// --mill-model FILE: the simulated mill cuts with that model's structure and
// cutting law (e.g. cell/models/paper_face_mill_mismatched.textproto: a
// softer tool, harder material) and the study's cutter and part (runout,
// width); the critical depth and the depths stay the configuration's, as a
// cell would plan them.
// Progress on stderr; SMC_STUDY_TRACE=T prints the windows around time T.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/modules.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/machining/model.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc_config.pb.h"
#include "study_grid.hpp"

using namespace smc::edge;

namespace {

struct Outcome {
  double contact_s = -1, leave_s = -1;  // first and last revolution in contact
  double detected_s = -1;               // N's event
  double chatter_s = -1;                // E's first event (speed change or added pass)
  uint64_t judged_revs = 0;             // revolutions N was active, before any chatter
  uint64_t chatter_revs = 0;            // revolutions N was active after chatter
  double largest_score = 0;             // of the revolutions judged
  double break_at_s = -1;               // when the tooth breaks (a break run)
  double break_score = 0;               // N's score when it fired
  double feed_at_break = 0;             // feed per tooth commanded when the tooth broke
  double force_at_break = -1;           // N's mean window force then
  bool completed = false;
  bool false_after_chatter = false;  // an intact cutter's detection after a chatter
};

// `mill_model`: the mill that cuts (the configuration's model, or
// --mill-model's with the study's width and runout).
Outcome run_one(const smc::config::SupervisorConfig& raw,
                const smc::config::MillingModel& mill_model, bool verbose, double break_at_s = -1) {
  EdgeConfig cfg = edge_config_from_proto(raw);
  SimulatedMill mill(mill_model, raw.simulation(), cfg.params.sample_period_s);
  EdgeCore core(cfg, mill);
  core.start();
  // A shadow of N fed the samples N is fed, for its scores.
  ToolBreakageDetector shadow;
  shadow.configure(cfg.params);
  shadow.reset();
  Signals scratch;
  Outcome o;
  o.break_at_s = break_at_s;
  uint32_t last_rev = 0;
  RunOptions opts;
  opts.max_time_s = 200;
  opts.keep_samples = false;
  opts.on_tick = [&](const EdgeCore& c) {
    const Signals& s = c.signals();
    if (s.chatter_detected && o.chatter_s < 0) o.chatter_s = s.sample.t_s;
    if (s.tool_broken && o.detected_s < 0) {
      o.detected_s = s.sample.t_s;
      if (o.break_at_s >= 0) o.break_score = s.breakage_drop;
      if (verbose)
        std::fprintf(stderr, "\n  N: window %d dropped %.3f at %.4f s (feed %.4f mm/tooth)\n",
                     s.breakage_window, s.breakage_drop, s.sample.t_s, s.feed_per_tooth_cmd_mm);
    }
    if (o.break_at_s >= 0 && o.force_at_break < 0 && s.sample.t_s >= o.break_at_s) {
      o.feed_at_break = s.feed_per_tooth_cmd_mm;
      double total = 0;
      for (int k = 0; k < cfg.params.teeth; ++k) total += shadow.window_means()[k];
      o.force_at_break = total / cfg.params.teeth;
    }
    if ((s.active & bit(ModuleId::N)) == 0) return;
    scratch = s;
    scratch.tool_broken = false;
    (void)shadow.on_sample(scratch);
    if (s.revolutions != last_rev) {
      last_rev = s.revolutions;
      const double score = shadow.take_largest_score();
      if (std::getenv("SMC_STUDY_TRACE") != nullptr) {
        const double t0 = std::atof(std::getenv("SMC_STUDY_TRACE"));
        if (std::fabs(s.sample.t_s - t0) < 0.3) {
          std::fprintf(stderr, "    t %.3f E %.3f f %.4f score %.3f:", s.sample.t_s,
                       s.chatter_ratio, s.feed_per_tooth_cmd_mm, score);
          for (int k = 0; k < cfg.params.teeth; ++k)
            std::fprintf(stderr, " %7.1f/%+6.1f", shadow.window_means()[k],
                         shadow.window_changes()[k]);
          std::fprintf(stderr, "\n");
        }
      }
      if (o.chatter_s < 0 && o.detected_s < 0) {
        ++o.judged_revs;
        o.largest_score = std::max(o.largest_score, score);
        if (verbose && score > 0.5 * cfg.params.breakage_threshold) {
          std::fprintf(stderr, "    t %.3f score %.3f\n", s.sample.t_s, score);
        }
      } else if (o.detected_s < 0) {
        ++o.chatter_revs;
      }
    }
  };
  RunResult run = run_virtual(core, opts);
  o.completed = run.completed;
  for (const auto& e : run.events) {
    if (e.kind == EventKind::kToolBroken && o.detected_s < 0) o.detected_s = e.t_s;
    if ((e.kind == EventKind::kChatterDetected || e.kind == EventKind::kChatterSignalled) &&
        o.chatter_s < 0)
      o.chatter_s = e.t_s;
  }
  o.false_after_chatter =
      o.break_at_s < 0 && o.detected_s >= 0 && o.chatter_s >= 0 && o.detected_s >= o.chatter_s;
  for (const auto& r : run.revolutions) {
    if (!r.contact) continue;
    if (o.contact_s < 0) o.contact_s = r.t_s;
    o.leave_s = r.t_s;
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  smc::bench::StudyGrid grid;
  int tooth = 2;
  double critical_feed = 0.03;
  // When the tooth breaks: a share of the path in contact, or revolutions
  // after the first revolution in contact.
  struct Timing {
    double value;
    bool revolutions;
    std::string label;
  };
  std::vector<Timing> timings{{0.1, false, "entry"}, {0.5, false, "steady"}, {0.9, false, "exit"}};
  CLI::App app{
      "smc-bench-breakage: module N (tool-breakage detector) under SMC II+ on the simulated "
      "mill. Each cut\n"
      "runs once with the intact cutter (false detections, N's margin) and once per break "
      "timing with a\n"
      "tooth losing its edge (delay from the break to N's detection, in revolutions). "
      "Progress on stderr.\n"
      "Figures: edge/README.md, \"Modules beyond Table 1\"; details: the head of "
      "tests/bench/edge/breakage_study.cpp."};
  grid.add_options(app, ", runouts 0 and 20 um");
  app.add_option("--critical-feed", critical_feed,
                 "mm/tooth at which the critical depths are found (near the feed the force "
                 "controller settles at)")
      ->check(smc::bench::kPositive)
      ->capture_default_str();
  app.add_option("--tooth", tooth, "the tooth that breaks")
      ->check(smc::bench::kPositive)
      ->capture_default_str();
  std::string timing_list;
  app.add_option("--timings", timing_list,
                 "when the tooth breaks: shares of the path in contact (0-1), or revolutions "
                 "after contact with a trailing r, comma-separated (0.1,0.5,0.9)");
  CLI11_PARSE(app, argc, argv);
  grid.finish(app);
  if (!timing_list.empty()) {
    timings.clear();
    std::stringstream in(timing_list);
    std::string item;
    while (std::getline(in, item, ',')) {
      const bool revs = !item.empty() && item.back() == 'r';
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      const bool whole =
          end != item.c_str() && (*end == '\0' || (revs && end[0] == 'r' && end[1] == '\0'));
      if (!whole || !(v >= 0) || (!revs && v > 1)) {
        std::fprintf(stderr,
                     "--timings %s: each timing is a share of the path in contact (0-1) or "
                     "revolutions after contact with a trailing r (e.g. 0.1,0.5,2r)\n",
                     item.c_str());
        return 2;
      }
      timings.push_back({v, revs, item});
    }
  }
  if (grid.quick && app.count("--runouts") == 0) grid.runouts = {0, 20};
  const auto& speeds = grid.speeds;
  const auto& widths = grid.widths;
  const auto& fractions = grid.fractions;
  const auto& runouts = grid.runouts;
  const int seeds = grid.seeds;
  const bool verbose = grid.verbose;
  auto base = smc::documents::load_supervisor_config(std::string(SMC_SOURCE_DIR) +
                                                     "/edge/configs/smc2_plus.textproto");
  smc::config::MillingModel plant;
  if (!grid.load_mill_model(plant)) return 2;
  const std::string& mill_model_file = grid.mill_model_file;
  const double fpt = 0.1;
  const double threshold = edge_config_from_proto(base).params.breakage_threshold;
  const double floor_n = ToolBreakageDetector::force_floor_n(edge_config_from_proto(base).params);
  const double dt = edge_config_from_proto(base).params.sample_period_s;
  std::printf(
      "module N: threshold %.2f (a tooth window's fall beyond the common change, share of the "
      "mean window); tooth %d loses its edge (with runout, tooth 1 stands out furthest); "
      "programmed %.2f mm/tooth, depths as fractions of the critical depth at %.3f mm/tooth, "
      "%d seed(s); the mill cuts with %s\n\n",
      threshold, tooth, fpt, critical_feed, seeds,
      mill_model_file.empty() ? "the configuration's model" : mill_model_file.c_str());
  std::printf("%6s %6s %6s %7s %5s %9s %7s %9s", "rpm", "width", "runout", "depth", "runs",
              "intact_rv", "false", "max_score");
  for (const auto& t : timings) std::printf(" %9s", (t.label + "_rv").c_str());
  std::printf(" %7s\n", "missed");
  uint64_t all_revs = 0, all_chatter_revs = 0;
  int all_light = 0, light_detected = 0, all_floor = 0, floor_detected = 0;
  int all_false = 0, all_false_chatter = 0, all_breaks = 0, all_detected = 0, all_within = 0;
  double all_max = 0, worst_delay = 0, min_break_score = 1e9;
  for (double rpm : speeds) {
    for (double width : widths) {
      auto model_msg = base.milling_model();
      model_msg.mutable_workpiece()->set_width_mm(width);
      const auto model = smc::machining::from_proto(model_msg, "study");
      smc::machining::TdsSearchOptions so;
      so.relative_tolerance = 2e-2;
      so.max_depth_mm = 20;
      const double crit =
          smc::machining::critical_depth_tds(model, rpm, critical_feed, so).critical_depth_mm;
      const auto plain_msg = model_msg;
      for (double runout : runouts) {
        model_msg = plain_msg;
        if (runout > 0) {
          for (const double r : smc::machining::eccentric_runout_um(
                   static_cast<int>(model_msg.cutter().teeth()), runout)) {
            model_msg.mutable_cutter()->add_radial_runout_um(r);
          }
        }
        // The mill that cuts: the configuration's model, or --mill-model's
        // structure and cutting law with this cutter (runout) and part
        // (width), as `smc-edge simulate --mill-model` takes it; the depths
        // stay the configuration's.
        auto mill_msg = model_msg;
        if (!mill_model_file.empty()) use_plant_model(mill_msg, plant);
        for (double fraction : fractions) {
          const double depth = fraction * crit;
          uint64_t revs = 0;
          int falses = 0, runs = 0, missed = 0;
          double max_score = 0;
          std::vector<double> delay(timings.size(), -1.0);
          for (int seed = 1; seed <= seeds; ++seed) {
            auto raw = base;
            *raw.mutable_milling_model() = model_msg;
            auto* pass = raw.mutable_program()->mutable_passes(0);
            pass->set_depth_mm(depth);
            pass->set_spindle_rpm(rpm);
            pass->set_feedrate_mm_s(fpt * raw.operation().teeth() * rpm / 60.0);
            raw.mutable_program()->set_total_depth_mm(depth);
            raw.mutable_simulation()->set_seed(static_cast<uint64_t>(seed));
            std::fprintf(stderr, "\r%4.0f rpm, %2.0f mm, runout %2.0f um, %.2f mm, intact    ", rpm,
                         width, runout, depth);
            const Outcome intact = run_one(raw, mill_msg, verbose);
            ++runs;
            revs += intact.judged_revs;
            all_chatter_revs += intact.chatter_revs;
            max_score = std::max(max_score, intact.largest_score);
            if (intact.false_after_chatter) {
              ++all_false_chatter;
              if (verbose)
                std::fprintf(stderr, "\n  FALSE detection at %.3f s, after chatter at %.3f s\n",
                             intact.detected_s, intact.chatter_s);
            } else if (intact.detected_s >= 0) {
              ++falses;
              if (verbose)
                std::fprintf(stderr, "\n  FALSE detection at %.3f s\n", intact.detected_s);
            }
            if (intact.contact_s < 0) continue;
            const double span = intact.leave_s - intact.contact_s;
            std::vector<double> at;
            for (const auto& t : timings) {
              at.push_back(intact.contact_s +
                           (t.revolutions ? t.value * 60.0 / rpm : t.value * span));
            }
            for (std::size_t k = 0; k < at.size(); ++k) {
              std::fprintf(stderr, "\r%4.0f rpm, %2.0f mm, runout %2.0f um, %.2f mm, break %s   ",
                           rpm, width, runout, depth, timings[k].label.c_str());
              auto broken = raw;
              auto* b = broken.mutable_simulation()->add_tooth_breaks();
              b->set_tooth(static_cast<uint32_t>(tooth));
              b->set_at_s(at[k]);
              const Outcome o = run_one(broken, mill_msg, verbose, at[k]);
              ++runs;
              // A break after a chatter (the speed moved) is not this study's case.
              if (o.chatter_s >= 0 && o.chatter_s < at[k]) continue;
              // The broken tooth's chip at the feed of the moment, share of
              // the mean (Kline and DeVor's runout kinematics): below N's
              // threshold the break removes too little force to be seen.
              double share = 1;
              if (runout > 0 && o.feed_at_break > 0) {
                std::vector<double> r_mm;
                for (int i = 0; i < model_msg.cutter().radial_runout_um_size(); ++i)
                  r_mm.push_back(1e-3 * model_msg.cutter().radial_runout_um(i));
                share = std::max(0.0, smc::machining::runout_chip_mm(
                                          r_mm.data(), static_cast<int>(r_mm.size()), tooth - 1,
                                          o.feed_at_break, 1.0)) /
                        o.feed_at_break;
              }
              if (o.force_at_break < floor_n) {
                ++all_floor;
                if (verbose)
                  std::fprintf(stderr, "\n  break at %.3f s with a mean window force of %.0f N\n",
                               at[k], o.force_at_break);
                if (o.detected_s >= at[k]) ++floor_detected;
                continue;
              }
              if (share < threshold) {
                ++all_light;
                if (verbose)
                  std::fprintf(stderr,
                               "\n  break at %.3f s of a tooth cutting %.0f %% of the mean chip\n",
                               at[k], 100 * share);
                if (o.detected_s >= at[k]) ++light_detected;
                continue;
              }
              ++all_breaks;
              if (o.detected_s < at[k]) {
                ++missed;
                if (verbose) std::fprintf(stderr, "\n  MISSED break at %.3f s\n", at[k]);
                continue;
              }
              ++all_detected;
              min_break_score = std::min(min_break_score, o.break_score);
              if (verbose)
                std::fprintf(stderr, "\n  break at %.3f s detected at %.3f s\n", at[k],
                             o.detected_s);
              const double d = (o.detected_s - at[k]) * rpm / 60.0;
              delay[k] = std::max(delay[k], d);
              worst_delay = std::max(worst_delay, d);
              // The first sample at which a revolution has passed (a part
              // of a sample's float error is no delay).
              const double by_s = dt * std::ceil((at[k] + 60.0 / rpm) / dt - 1e-6);
              if (o.detected_s <= by_s + 1e-9) {
                ++all_within;
              } else if (verbose) {
                std::fprintf(stderr,
                             "\n  LATE: break at %.5f s, a revolution passed at %.4f s, detected "
                             "at %.4f s\n",
                             at[k], by_s, o.detected_s);
              }
            }
          }
          all_revs += revs;
          all_false += falses;
          all_max = std::max(all_max, max_score);
          std::printf("%6.0f %6.0f %6.0f %7.2f %5d %9llu %7d %9.3f", rpm, width, runout, depth,
                      runs, static_cast<unsigned long long>(revs), falses, max_score);
          for (const double d : delay) std::printf(" %9.2f", d);
          std::printf(" %7d\n", missed);
          std::fflush(stdout);
        }
      }
    }
  }
  std::fprintf(stderr, "\n");
  std::printf(
      "\nintact cutters: %llu revolutions judged, %d false detections; largest score %.3f "
      "(margin: threshold / largest = %.2f); %llu revolutions after a chatter left out, %d "
      "detections in them\n",
      static_cast<unsigned long long>(all_revs), all_false, all_max,
      all_max > 0 ? threshold / all_max : 0.0, static_cast<unsigned long long>(all_chatter_revs),
      all_false_chatter);
  std::printf(
      "breaks: %d, detected %d, within 1 revolution %d; worst delay %.2f revolutions; smallest "
      "score at a detection %.3f (margin: smallest / threshold = %.2f)\n",
      all_breaks, all_detected, all_within, worst_delay, min_break_score,
      min_break_score / threshold);
  std::printf(
      "breaks of a tooth whose chip (with runout, at the feed of the moment) was below the "
      "threshold's share of the mean: %d, of them detected %d (not counted above)\n",
      all_light, light_detected);
  std::printf(
      "breaks while the mean window force was below N's floor (%.1f N = 0.75 x the contact "
      "threshold): %d, of them detected %d (not counted above)\n",
      floor_n, all_floor, floor_detected);
  const bool pass = all_false == 0 && all_revs >= 20000 && all_within == all_breaks;
  std::printf(
      "goal (every break within 1 revolution, 0 false detections in >= 20,000 intact "
      "revolutions): %s\n",
      pass ? "met" : "NOT met");
  return 0;
}
