// Inputs at and around every limit, seeded and repeatable: job files and
// configuration documents with field lengths and values just under, at and
// just over each limit. Every input is either accepted — and then fits the
// wire and can be planned, validated and, for a sample, run to completion in
// virtual time — or refused with a message for every problem.

#include "smc/wire/limits.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "smc/cell/planner.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/supervision/config.hpp"

namespace cell = smc::cell;
namespace store = smc::cell::store;
namespace cfg = smc::config;
namespace sv = smc::supervision;

namespace {

std::string src(const std::string& rel) { return std::string(SMC_SOURCE_DIR) + "/" + rel; }

template <class T>
T pick(std::mt19937& rng, std::initializer_list<T> options) {
  std::uniform_int_distribution<size_t> d(0, options.size() - 1);
  return *(options.begin() + static_cast<std::ptrdiff_t>(d(rng)));
}

void expect_one_line_messages(const smc::common::Diagnostics& problems, const std::string& what) {
  ASSERT_FALSE(problems.empty()) << what;
  for (const auto& d : problems) {
    EXPECT_FALSE(d.message.empty()) << what;
    EXPECT_EQ(d.str().find('\n'), std::string::npos) << d.str();
    EXPECT_LT(d.str().size(), 2000u) << "a value echoed whole: " << what;
  }
}

}  // namespace

TEST(Limits, JobsAroundEveryLimitAreAcceptedAndCarriedOrRefusedWithReasons) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-limits-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto db = store::Store::open((dir / "cell.db").string());
  store::seed_demo(db);
  cfg::SupervisorConfig defaults;
  smc::documents::load(src("cell/configs/defaults.textproto"), defaults);
  const cell::Planner planner(src("cell/grafcets"), defaults);
  const store::Machine machine = *db.machine("mill-1");

  std::mt19937 rng(20261124);
  int accepted = 0, refused = 0, planned = 0, ran = 0, completed = 0;
  for (int i = 0; i < 200; ++i) {
    cfg::Job j;
    const size_t id_len = pick<size_t>(rng, {0, 0, 0, 1, 47, 48, 48, 49, 63, 64, 65, 5000});
    if (id_len > 0) j.set_job_id("j" + std::string(id_len - 1, static_cast<char>('a' + i % 26)));
    j.set_part_id(pick<std::string>(
        rng, {"housing-js", "housing-js", "bracket-tl", "", "nope", std::string(300, 'p')}));
    j.set_depth_mm(pick<double>(rng, {2, 2, 0, 0.5, -1, 1e-9, 49.9, 50, 1e9, NAN}));
    j.set_feedrate_mm_s(pick<double>(rng, {10, 10, 0, 5, 35.9, 36, 36.1, -3, INFINITY}));
    j.set_spindle_rpm(pick<double>(rng, {1500, 1500, 0, 2999, 3000, 3001, -1500}));
    j.set_machine_id(pick<std::string>(rng, {"", "", "mill-1", "mill-9", std::string(32, 'm')}));
    const std::string what = "job " + std::to_string(i);
    try {
      const store::Job stored = db.submit_job(j);
      ++accepted;
      EXPECT_LE(stored.id.size(), smc::wire::kJobIdMax) << what;
      EXPECT_LE(stored.spec.machine_id().size(), smc::wire::kMachineIdMax) << what;
      // The cell's next steps: select, plan, validate the configuration it would send.
      cell::PlanInputs in{
          stored, *db.part(stored.spec.part_id()), *db.tool(stored.spec.tool_id()),
          db.find_models("mill-1", stored.spec.tool_id(),
                         db.part(stored.spec.part_id())->material_id, stored.spec.part_id())};
      const auto sel = cell::select_variant(in);
      cell::Plan plan;
      try {
        plan = planner.plan(in, sel);
      } catch (const std::exception& e) {  // the cell fails the job with this reason
        EXPECT_GT(std::string(e.what()).size(), 10u) << what;
        continue;
      }
      const auto config =
          cell::Planner::for_machine(plan.config, machine, stored.id + "-a" + std::to_string(1));
      sv::ValidatedConfig vc;
      try {
        vc = sv::validate(config);
      } catch (const sv::ConfigError& e) {  // likewise
        expect_one_line_messages(e.diagnostics(), what);
        continue;
      }
      ++planned;
      EXPECT_LE(vc.config_id.size(), smc::wire::kConfigIdMax) << what;
      // A sample of the accepted jobs runs to the end on the simulated mill.
      if (ran < 6 && sel.variant == cfg::SMC_II) {
        // The mill's own model (as `smc-edge run --mill-model` gives it),
        // cutting the job's part geometry.
        cfg::MillingModel own;
        smc::documents::load(src("cell/models/paper_face_mill.textproto"), own);
        *own.mutable_cutter() = config.milling_model().cutter();
        *own.mutable_workpiece() = config.milling_model().workpiece();
        smc::edge::SimulatedMill mill(own, config.simulation(), vc.params.sample_period_s);
        smc::edge::EdgeCore core(smc::edge::edge_config_from_proto(config), mill);
        core.start();
        smc::edge::RunOptions opts;
        opts.keep_samples = false;
        opts.max_time_s = 120;
        const auto run = smc::edge::run_virtual(core, opts);
        // It completes, or the mill ends in a safe state with its reason: a
        // single pass far deeper than the cutter can take (49.9 mm, which the
        // catalog does not forbid: no per-tool depth limit yet) saturates the
        // force sensor, or chatters on until the suppressor's program is full
        // (16 passes), and the feed is held.
        EXPECT_TRUE(run.completed || (core.fault_hold() && core.fault() != smc::edge::Fault::kNone))
            << what << ": " << stored.spec.ShortDebugString() << " ended at " << run.end_time_s
            << " s, fault " << smc::edge::to_string(core.fault()) << " s";
        completed += run.completed ? 1 : 0;
        ++ran;
      }
    } catch (const store::JobRejected& e) {
      ++refused;
      expect_one_line_messages(
          [&] {
            smc::common::Diagnostics d;
            for (const auto& f : e.errors) d.add(f);
            return d;
          }(),
          what);
    }
  }
  EXPECT_GT(accepted, 5);
  EXPECT_GT(refused, 50);
  EXPECT_GT(planned, 3);
  EXPECT_GT(ran, 0);
  EXPECT_GT(completed, 0);
  std::filesystem::remove_all(dir);
}

TEST(Limits, ConfigurationsAroundEveryLimitAreValidOrRefusedWithReasons) {
  const cfg::SupervisorConfig base =
      smc::documents::load_supervisor_config(src("edge/configs/smc2.textproto"));
  std::mt19937 rng(7);
  int valid = 0, refused = 0;
  for (int i = 0; i < 120; ++i) {
    cfg::SupervisorConfig c = base;
    const size_t id_len = pick<size_t>(rng, {8, 8, 1, 62, 63, 63, 64, 200, 0});
    c.set_config_id(std::string(id_len, 'c'));
    const int passes = pick<int>(rng, {1, 1, 2, 16, 16, 17, 40, 0});
    const auto pass = base.program().passes(0);
    c.mutable_program()->clear_passes();
    for (int k = 0; k < passes; ++k) {
      auto* p = c.mutable_program()->add_passes();
      *p = pass;
      p->set_depth_mm(2.0 / passes);
    }
    if (passes > 0) {
      c.mutable_program()->mutable_passes(0)->set_feedrate_mm_s(
          pick<double>(rng, {10, 10, 35.9, 36, 36.1, 0, NAN}));
    }
    const size_t pad = pick<size_t>(
        rng, {0, 0, 0, 65536 - c.grafcet_text().size(), 65537 - c.grafcet_text().size(), 1u << 20});
    if (pad > 0) c.set_grafcet_text(c.grafcet_text() + "\n#" + std::string(pad - 2, 'x'));
    c.mutable_operation()->set_sample_period_s(
        pick<double>(rng, {0.0005, 0.0005, 0.0005, 1e-12, 0, 0.01}));
    try {
      const sv::ValidatedConfig vc = sv::validate(c);
      ++valid;
      EXPECT_LE(vc.config_id.size(), smc::wire::kConfigIdMax);
      EXPECT_LE(vc.program.count, sv::kMaxPasses);
      EXPECT_LE(vc.grafcet_text.size(), 64u * 1024);
    } catch (const sv::ConfigError& e) {
      ++refused;
      expect_one_line_messages(e.diagnostics(), "configuration " + std::to_string(i));
    }
  }
  EXPECT_GT(valid, 3);
  EXPECT_GT(refused, 50);
}
