// smc-edge simulate / check: offline runs of the edge on the simulated mill.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "commands.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/linuxcnc_drive.hpp"
#include "smc/edge/replay_drive.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/machining/model.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc_config.pb.h"

namespace smc::edge::cli {

namespace {

struct SimulateArgs {
  std::string config;
  std::string out = "out/simulate";
  std::vector<std::string> feed_holds;
  std::vector<double> chatter_at;
  std::string replay;
  std::string mill_model;
  double max_time_s = 600;
  double feed_lag_ms = -1;  // < 0: as the configuration says
  double plant_gain = 1;
  double runout_um = 0;
  std::vector<std::string> breaks;
  double wear_per_m = -1;
  bool quiet = false;
  std::string drive = "sim";
  std::string program_dir = "/tmp/smc-programs";
};

// The simulated mill's cutting coefficients times `gain`: a plant whose
// force per chip differs from the models the configuration carries.
void scale_cutting_law(smc::config::MillingModel& m, double gain) {
  auto* law = m.mutable_law();
  if (law->has_power_law()) {
    auto* p = law->mutable_power_law();
    p->mutable_cutting()->set_coefficient_kn_per_mm2(p->cutting().coefficient_kn_per_mm2() * gain);
    p->mutable_thrust()->set_coefficient_kn_per_mm2(p->thrust().coefficient_kn_per_mm2() * gain);
  } else if (law->has_linear()) {
    auto* l = law->mutable_linear();
    l->set_k_t_n_per_mm2(l->k_t_n_per_mm2() * gain);
    l->set_k_n_n_per_mm2(l->k_n_n_per_mm2() * gain);
    l->set_k_a_n_per_mm2(l->k_a_n_per_mm2() * gain);
  }
}

EdgeConfig load_config(const std::string& path, smc::config::SupervisorConfig& raw) {
  try {
    raw = smc::documents::load_supervisor_config(path);
    return edge_config_from_proto(raw);
  } catch (const ConfigError& e) {
    throw Failure(2, path + ": " + e.what());
  } catch (const smc::documents::DocumentError& e) {
    throw Failure(2, e.what());
  }
}

void print_summary(const smc::config::RunSummary& s, const std::string& out) {
  std::printf("%s: %s in %.2f s of machine time, %u of %u planned passes (%u rewrite%s)\n",
              s.config_id().c_str(), s.completed() ? "completed" : "NOT completed",
              s.cycle_time_s(), s.passes_completed(), s.passes_planned(), s.program_rewrites(),
              s.program_rewrites() == 1 ? "" : "s");
  std::printf("  F_ref %.1f N; peak F_Y %.1f N (%+.0f %% of F_ref); ", s.force_reference_n(),
              s.peak_force_n(), s.peak_force_violation_pct());
  if (s.peak_power_w() > 0) {
    std::printf("peak spindle power %.0f W (%+.0f %% of the limit)\n", s.peak_power_w(),
                s.peak_power_violation_pct());
  } else {
    // A drive without a power signal (LinuxCNC, a replay): only M's estimate.
    std::printf("spindle power not measured by this drive; steady mean (estimated) %.0f W\n",
                s.steady_mean_power_w());
  }
  std::printf("  overshoot %.1f %%; steady-state error %.1f %%; chatter events %u",
              s.overshoot_pct(), s.steady_state_error_pct(), s.chatter_events());
  if (s.chatter_onset_s() >= 0) std::printf("; onset %.2f s", s.chatter_onset_s());
  if (s.chatter_detected_s() >= 0) std::printf("; detected %.2f s", s.chatter_detected_s());
  if (s.detection_delay_s() >= 0)
    std::printf(" (%.0f ms after onset)", 1000 * s.detection_delay_s());
  std::printf("\n");
  if (s.spindle_speed_changes() > 0) {
    std::printf("  spindle speed changed %u time(s) against chatter; last pass at %.0f rpm\n",
                s.spindle_speed_changes(), s.final_spindle_rpm());
  }
  if (s.tool_broken_s() >= 0) {
    std::printf("  TOOL BROKEN: module N stopped the feed at %.4f s\n", s.tool_broken_s());
  }
  for (const auto& f : s.faults()) std::printf("  fault: %s\n", f.c_str());
  std::printf(
      "  wrote %s/{samples.csv,revolutions.csv,events.csv,summary.json,force.svg,"
      "feed.svg,raw.svg}\n",
      out.c_str());
}

}  // namespace

void add_tooth_break(const std::string& spec, smc::config::SimulatedMill& sim) {
  unsigned tooth = 0;
  double at = -1, loss = 0;
  int used = 0;
  const int n = std::sscanf(spec.c_str(), "%u@%lf%n:%lf%n", &tooth, &at, &used, &loss, &used);
  if (n < 2 || used != static_cast<int>(spec.size()) || tooth == 0 || !(at >= 0) || !(loss >= 0)) {
    throw Failure(2, "--break-tooth " + spec + ": give T@S or T@S:MM (tooth from 1, time " +
                         "in s, edge lost in mm), e.g. 2@12.5 or 2@12.5:0.05");
  }
  auto* b = sim.add_tooth_breaks();
  b->set_tooth(tooth);
  b->set_at_s(at);
  b->set_edge_loss_mm(loss);
}

void add_simulate(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Run one part program in virtual time on the simulated mill (or a recorded force file)\n"
      "and write per-sample and per-revolution CSV, a JSON summary and SVG plots. With\n"
      "--drive linuxcnc the same run is cut in real time by the LinuxCNC running on this host\n"
      "(deploy/linuxcnc/run.sh start --dyno CONFIG), with the same outputs. Exit 0: the\n"
      "program completed; 3: not within --max-time; 4: LinuxCNC fault; 5: the tool broke\n"
      "(module N held the feed; the run stops a second later).");
  sub->add_option("--config", args->config,
                  "Supervisor configuration (textproto or JSON), e.g.\n"
                  "edge/configs/smc2.textproto")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--out", args->out, "Output folder (created)")->capture_default_str();
  sub->add_option("--feed-hold-at", args->feed_holds,
                  "Operator feed hold T:DURATION in seconds of machine time (repeatable)");
  sub->add_option("--chatter-at", args->chatter_at,
                  "Operator chatter signal at T seconds (repeatable)");
  sub->add_option("--replay", args->replay,
                  "Play recorded force from this CSV instead of simulating the mill")
      ->check(CLI::ExistingFile);
  sub->add_option("--mill-model", args->mill_model,
                  "Simulate this mill (a MillingModel textproto: structure and cutting law; the\n"
                  "configuration's cutter and workpiece are kept) instead of the configuration's\n"
                  "milling_model: a plant that is not the models the plan was made from")
      ->check(CLI::ExistingFile);
  sub->add_option("--max-time", args->max_time_s, "Stop after this many seconds")
      ->capture_default_str();
  sub->add_option("--feed-lag-ms", args->feed_lag_ms,
                  "Feed drive lag of the simulated mill (first-order time constant, ms); "
                  "default: the configuration's simulation.feed_drive_lag_s")
      ->check(CLI::Range(0.0, 1000.0));
  sub->add_option("--plant-gain", args->plant_gain,
                  "Scale the simulated mill's cutting coefficients (a plant that is not the "
                  "model: L's force model and the plan stay as configured)")
      ->check(CLI::Range(0.05, 20.0))
      ->capture_default_str();
  sub->add_option("--runout-um", args->runout_um,
                  "Cutter runout of the simulated mill: the cutter mounted off-axis by this many\n"
                  "micrometres (tooth 0 furthest out), the teeth cutting unequal chips; 0: none")
      ->check(CLI::Range(0.0, smc::machining::kMaxRunoutUm))
      ->capture_default_str();
  sub->add_option("--break-tooth", args->breaks,
                  "Tooth T (1-based) breaks at S s of machine time: T@S loses its edge, T@S:MM\n"
                  "chips MM mm of it (repeatable), e.g. --break-tooth 2@12.5");
  sub->add_option("--wear-per-m", args->wear_per_m,
                  "The cutting pressures grow by this share per metre of cut (e.g. 0.05)")
      ->check(CLI::Range(0.0, 10.0));
  sub->add_flag("--quiet", args->quiet, "Print nothing but errors");
  sub->add_option("--drive", args->drive,
                  "sim (the simulated mill, virtual time) or linuxcnc (the running LinuxCNC, real\n"
                  "time; run as its user: deploy/linuxcnc/run.sh exec smc-edge simulate ...)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "linuxcnc"}));
  sub->add_option("--program-dir", args->program_dir,
                  "Where the G-code handed to LinuxCNC is written (--drive linuxcnc)")
      ->capture_default_str();
  sub->callback([args] {
    smc::config::SupervisorConfig raw;
    EdgeConfig cfg = load_config(args->config, raw);
    if (smc::supervision::chatter_detector_without_structure(raw)) {
      std::fprintf(stderr,
                   "smc-edge: %s: warning: module E runs with no structure in y "
                   "(milling_model.structure.tool_y, part_y), so it judges the force spectrum "
                   "alone; give it the machine's structure for its vibration estimate\n",
                   args->config.c_str());
    }
    if (const auto w = smc::supervision::wideband_channel_warning(raw); !w.empty()) {
      std::fprintf(stderr, "smc-edge: %s: warning: %s\n", args->config.c_str(), w.c_str());
    }
    if (args->drive != "linuxcnc" && args->replay.empty()) {
      try {
        check_wideband_channel_agrees(raw);  // the configuration as given, before the plant's
      } catch (const ConfigError& e) {
        throw Failure(2, args->config + ": " + e.what());
      }
    }
    if (args->feed_lag_ms >= 0) {
      raw.mutable_simulation()->set_feed_drive_lag_s(args->feed_lag_ms / 1000.0);
    }
    if (!args->mill_model.empty()) {
      smc::config::MillingModel plant;
      try {
        smc::documents::load(args->mill_model, plant);
      } catch (const smc::documents::DocumentError& e) {
        throw Failure(2, e.what());
      }
      use_plant_model(*raw.mutable_milling_model(), std::move(plant));
    }
    if (args->plant_gain != 1) scale_cutting_law(*raw.mutable_milling_model(), args->plant_gain);
    if (args->runout_um > 0) {
      auto* cutter = raw.mutable_milling_model()->mutable_cutter();
      cutter->clear_radial_runout_um();
      for (const double r : smc::machining::eccentric_runout_um(
               static_cast<int>(std::max<std::uint32_t>(cutter->teeth(), 1)), args->runout_um)) {
        cutter->add_radial_runout_um(r);
      }
    }
    for (const auto& spec : args->breaks) add_tooth_break(spec, *raw.mutable_simulation());
    if (args->wear_per_m >= 0) raw.mutable_simulation()->set_wear_per_m(args->wear_per_m);
    RunOptions opts;
    opts.max_time_s = args->max_time_s;
    for (const auto& spec : args->feed_holds) {
      try {
        for (const auto& in : parse_feed_hold(spec)) opts.inputs.push_back(in);
      } catch (const std::invalid_argument& e) {
        throw Failure(2, e.what());
      }
    }
    for (double t : args->chatter_at) opts.inputs.push_back({ScheduledInput::kChatterSignal, t});
    std::unique_ptr<Drive> drive;
    LinuxCncDrive* cnc = nullptr;
    try {
      if (args->drive == "linuxcnc") {
        if (!args->replay.empty() || !args->mill_model.empty() || args->plant_gain != 1 ||
            args->runout_um > 0 || !args->breaks.empty() || args->wear_per_m >= 0) {
          throw Failure(2,
                        "--drive linuxcnc: the plant is LinuxCNC's (its dynamometer: "
                        "run.sh start --dyno CONFIG [--plant MODEL]); --replay, --mill-model, "
                        "--plant-gain and --runout-um are for the simulated mill");
        }
        LinuxCncDriveOptions lo;
        lo.machine_id = "smc-simulate";
        lo.program_dir = args->program_dir;
        auto d = std::make_unique<LinuxCncDrive>(raw, cfg.params.sample_period_s, lo);
        cnc = d.get();
        drive = std::move(d);
      } else if (!args->replay.empty()) {
        drive = std::make_unique<ReplayDrive>(args->replay, cfg.params.sample_period_s);
      } else {
        drive = std::make_unique<SimulatedMill>(raw.milling_model(), raw.simulation(),
                                                cfg.params.sample_period_s);
      }
    } catch (const ConfigError& e) {
      throw Failure(2, args->config + ": " + e.what());
    } catch (const std::runtime_error& e) {
      throw Failure(2, e.what());
    }
    EdgeCore core(cfg, *drive);
    try {
      core.start();
    } catch (const std::runtime_error& e) {
      throw Failure(2, e.what());  // LinuxCNC not ready, or refused the program
    }
    // On LinuxCNC: the loop's pacing, tick to tick on the wall clock, and the
    // servo records waiting when a tick starts (allocated before the run).
    std::vector<double> intervals_ms;
    int max_backlog = 0;
    if (cnc != nullptr) {
      intervals_ms.reserve(static_cast<std::size_t>(args->max_time_s / cfg.params.sample_period_s) +
                           1);
      opts.before_tick = [cnc, &intervals_ms, &max_backlog,
                          last = std::chrono::steady_clock::time_point{}]() mutable {
        (void)cnc->wait_sample();
        const auto now = std::chrono::steady_clock::now();
        if (last.time_since_epoch().count() != 0 && intervals_ms.size() < intervals_ms.capacity()) {
          intervals_ms.push_back(std::chrono::duration<double, std::milli>(now - last).count());
        }
        last = now;
        max_backlog = std::max(max_backlog, cnc->backlog());
        return cnc->fault().empty();
      };
    }
    const auto t0 = std::chrono::steady_clock::now();
    double next_report = 5.0;
    opts.on_tick = [&](const EdgeCore& c) {
      const double t = c.drive_sample().force.t_s;
      if (!args->quiet && t >= next_report) {
        std::fprintf(stderr, "\r  t = %5.1f s, pass %d of %d ...", t,
                     c.drive_sample().pass_index + 1, c.program().count);
        next_report += 5.0;
      }
    };
    RunResult run = run_virtual(core, opts);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!args->quiet) std::fprintf(stderr, "\r%60s\r", "");
    const auto summary = summarize(core, run);
    write_outputs(args->out, core, run, summary);
    if (!args->quiet) {
      print_summary(summary, args->out);
      std::printf("  %.1f s of machine time in %.2f s (%.0fx real time)\n", run.end_time_s, wall,
                  run.end_time_s / std::max(wall, 1e-9));
    }
    if (cnc != nullptr) {
      if (!args->quiet) {
        std::printf("  LinuxCNC servo records: %llu read, %llu lost, %llu repeated\n",
                    static_cast<unsigned long long>(cnc->samples()),
                    static_cast<unsigned long long>(cnc->lost_samples()),
                    static_cast<unsigned long long>(cnc->repeated_samples()));
        if (!intervals_ms.empty()) {
          std::sort(intervals_ms.begin(), intervals_ms.end());
          auto q = [&](double p) {
            return intervals_ms[std::min(
                intervals_ms.size() - 1,
                static_cast<std::size_t>(p * static_cast<double>(intervals_ms.size())))];
          };
          std::printf(
              "  loop paced by the servo thread: tick interval p50 %.3f ms, p99 %.3f ms, "
              "max %.3f ms; at most %d records waiting\n",
              q(0.5), q(0.99), intervals_ms.back(), max_backlog);
        }
      }
      const std::string why = cnc->fault();
      if (!why.empty()) throw Failure(4, "LinuxCNC: " + why + " (the feed is held)");
    }
    if (run.tool_broken_s >= 0) {
      throw Failure(5, "the tool broke at " + std::to_string(run.tool_broken_s) +
                           " s (module N); the feed is held and the job fails");
    }
    if (!run.completed) throw Failure(3, "the program did not complete within --max-time");
  });
}

void add_check(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "check", "Validate a supervisor configuration (parameters, program, Grafcet) and exit");
  sub->add_option("CONFIG", *path, "textproto or JSON")->required()->check(CLI::ExistingFile);
  sub->callback([path] {
    smc::config::SupervisorConfig raw;
    const EdgeConfig cfg = load_config(*path, raw);
    std::printf("%s: ok (%s, %d pass%s, Grafcet %s)\n", path->c_str(), cfg.config_id.c_str(),
                cfg.program.count, cfg.program.count == 1 ? "" : "es", cfg.grafcet_name.c_str());
  });
}

}  // namespace smc::edge::cli
