// smc-cell serve / plan: the cell service, and one job's plan offline.

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "registry.hpp"
#include "smc/cell/candidates.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/service.hpp"
#include "smc/cell/store/job_file.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/supervision/parameters.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

std::string data_dir(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("SMC_CELL_DATA"); env != nullptr && *env != '\0') return env;
  return SMC_CELL_DATA_DIR;
}

}  // namespace

SMC_CELL_COMMAND(serve, 10) {
  auto opt = std::make_shared<smc::cell::ServiceOptions>();
  auto data = std::make_shared<std::string>();
  auto grace_ms = std::make_shared<int>(6000);
  opt->db_path = smc::cell::store::default_db_path();
  CLI::App* sub = app.add_subcommand(
      "serve",
      "Run the cell service: plan queued jobs (SMC I or SMC II, explained), configure and\n"
      "dispatch them to idle mills over DDS, track them to the end, persist every change.\n"
      "Jobs reach it through the database (smc-cell job submit). Stops on SIGINT/SIGTERM.");
  sub->add_option("--db", opt->db_path, "Cell database (create it with smc-cell db init --seed)")
      ->capture_default_str();
  sub->add_option("--data", *data,
                  "Folder with grafcets/ and configs/ (default: the source tree's cell/)");
  sub->add_option("--domain", opt->domain_id, "DDS domain id")->capture_default_str();
  sub->add_option("--partition", opt->partition, "DDS partition (isolates a cell)");
  sub->add_option(
         "--edge-grace-ms", *grace_ms,
         "An edge silent this long (liveliness lost, or not seen since start) interrupts its job")
      ->capture_default_str();
  sub->add_option("--max-attempts", opt->max_attempts, "Attempts before an interrupted job fails")
      ->capture_default_str();
  sub->add_flag(
      "--paper-smc1", [opt](std::int64_t) { opt->guard_smc1 = false; },
      "Run SMC I jobs under the paper's smc1.grafcet (no chatter detector) instead of\n"
      "smc1_guarded.grafcet, which watches the cut and marks the plan's models suspect on chatter");
  sub->callback([opt, data, grace_ms] {
    const std::string dir = data_dir(*data);
    opt->grafcet_dir = dir + "/grafcets";
    opt->defaults_file = dir + "/configs/defaults.textproto";
    opt->edge_grace = std::chrono::milliseconds(*grace_ms);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    try {
      // A new service (a new DDS participant, state read again from the
      // database) when the last one was frozen past its lease.
      while (smc::cell::CellService(*opt).run(g_stop) == smc::cell::CellService::kRejoinDds) {
      }
    } catch (const smc::cell::store::StoreError& e) {
      throw smc::cell::cli::Failure(2, e.what());
    }
  });
}

SMC_CELL_COMMAND(plan, 11) {
  auto job_ref = std::make_shared<std::string>();
  auto db_path = std::make_shared<std::string>(smc::cell::store::default_db_path());
  auto data = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto paper_smc1 = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand(
      "plan",
      "Select SMC I or SMC II for a job and the machine whose models it uses, and plan it,\n"
      "without running it");
  sub->add_option("JOB", *job_ref, "A job file (textproto or JSON) or the id of a stored job")
      ->required();
  sub->add_option("--db", *db_path, "Cell database")->capture_default_str();
  sub->add_option("--data", *data, "Folder with grafcets/ and configs/");
  sub->add_option("--out", *out, "Write the planned SupervisorConfig here (textproto)");
  sub->add_flag("--paper-smc1", *paper_smc1,
                "Plan SMC I jobs for the paper's smc1.grafcet (no chatter detector) instead of "
                "smc1_guarded.grafcet");
  sub->callback([=] {
    const std::string dir = data_dir(*data);
    auto db = smc::cell::store::Store::open(*db_path, smc::cell::store::OpenMode::kExisting);
    smc::cell::store::Job job;
    if (auto stored = db.job(*job_ref)) {
      job = *stored;
    } else {
      job.id = "(file)";
      job.spec = smc::cell::store::load_job_file(*job_ref);
      const auto errors = db.validate_job(job.spec);
      if (!errors.empty()) {
        std::string msg = *job_ref + ":";
        for (const auto& e : errors) msg += "\n  " + e.str();
        throw smc::cell::cli::Failure(2, msg);
      }
      if (job.spec.spindle_rpm() == 0 || job.spec.tool_id().empty()) {
        // Fill the part's defaults as submission would.
        const auto part = db.part(job.spec.part_id());
        if (job.spec.tool_id().empty()) job.spec.set_tool_id(part->tool_id);
        if (job.spec.spindle_rpm() == 0) job.spec.set_spindle_rpm(part->spindle_rpm);
        if (job.spec.feedrate_mm_s() == 0) job.spec.set_feedrate_mm_s(part->feedrate_mm_s);
        if (job.spec.depth_mm() == 0) job.spec.set_depth_mm(part->total_depth_mm);
      }
    }
    smc::config::SupervisorConfig defaults;
    smc::documents::load(dir + "/configs/defaults.textproto", defaults);
    smc::cell::Planner planner(dir + "/grafcets", defaults,
                               smc::cell::PlannerOptions{.guard_smc1 = !*paper_smc1});
    smc::cell::Selection sel;
    const auto in = smc::cell::bind_job(db, job, sel);
    std::fprintf(stderr, "planning %s for %s ...\n",
                 std::string(smc::cell::store::variant_name(sel.variant)).c_str(),
                 in.machine.id.empty() ? "any machine" : in.machine.id.c_str());
    const auto plan = planner.plan(in, sel);
    std::printf("%s\n", plan.config.explanation().c_str());
    // The machine the job goes to: the plan's (SMC I), the one the job
    // names, or any.
    const std::string goes_to = !plan.machine_id.empty() ? plan.machine_id : job.spec.machine_id();
    std::printf("machine: %s\n", !plan.machine_id.empty() ? plan.machine_id.c_str()
                                 : !goes_to.empty() ? (goes_to + " (the job names it)").c_str()
                                                    : "any");
    std::printf("passes:");
    for (const auto& p : plan.config.program().passes()) std::printf(" %.3f mm", p.depth_mm());
    if (!plan.machine_id.empty()) {
      std::printf("\nfeeds (mm/tooth): programmed %.4f, equilibrium %.4f, lower clamp %.4f",
                  plan.programmed_feed_mm, plan.equilibrium_feed_mm, plan.lower_clamp_mm);
    }
    // A plan without a structure gets, at dispatch, its machine's for module
    // E (cell/README.md, "Module E's structure"): say which.
    const auto machines = [&] {
      std::vector<smc::cell::store::Machine> list;
      for (auto& m : db.machines()) {
        if (m.retired_at_ms == 0 && (goes_to.empty() || m.id == goes_to)) list.push_back(m);
      }
      return list;
    }();
    if (smc::supervision::chatter_detector_without_structure(plan.config)) {
      std::printf("\nmodule E's structure, given at dispatch:");
      for (const auto& m : machines) {
        const auto model = smc::cell::structure_model(db, job, m.id);
        std::printf(" %s: %s;", m.id.c_str(),
                    model ? ("model " + model->id).c_str() : "none (E judges S alone)");
      }
    }
    // A machine's own wideband channel replaces the defaults' at dispatch
    // (cell/README.md, "The machine's wideband channel").
    for (const auto& m : machines) {
      if (m.wideband.is_default()) continue;
      std::printf("\nmodule E's channel on %s, from its record: %s", m.id.c_str(),
                  smc::cell::store::channel_text(m.wideband).c_str());
    }
    // What the configuration each machine would get warns of (its channel
    // against the structure E then has).
    for (const auto& m : machines) {
      const auto model = smc::cell::structure_model(db, job, m.id);
      const auto sent =
          smc::cell::Planner::for_machine(plan.config, m, "(plan)", model ? &*model : nullptr);
      if (const auto w = smc::supervision::wideband_channel_warning(sent); !w.empty()) {
        std::printf("\nwarning on %s: %s", m.id.c_str(), w.c_str());
      }
    }
    std::printf("\nplanned in %.2f s\n", plan.planning_s);
    if (!out->empty()) {
      std::FILE* f = std::fopen(out->c_str(), "w");
      if (f == nullptr) throw smc::cell::cli::Failure(3, *out + ": cannot write");
      const std::string text = smc::documents::to_textproto(plan.config);
      std::fwrite(text.data(), 1, text.size(), f);
      std::fclose(f);
    }
  });
}
