// smc-cell job submit|list|show: job intake into the cell database
// (smc_cell_store). A submitted job is durable when `submit` returns; a
// running cell notices it through the database (cell/store/README.md).
// Exit codes: 0 ok, 1 the database cannot be used, 2 a bad job file, an
// unknown job or state.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "registry.hpp"
#include "smc/cell/candidates.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/store/job_file.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"

namespace {

using smc::cell::cli::add_db_option;
using smc::cell::cli::Failure;
namespace store = smc::cell::store;

std::string or_any(const std::string& s) { return s.empty() ? "any" : s; }

std::string all_states() {
  std::string s;
  for (int i = smc::config::JOB_QUEUED; i <= smc::config::JOB_INTERRUPTED; ++i) {
    s += (s.empty() ? "" : ", ") +
         std::string(store::state_name(static_cast<smc::config::JobState>(i)));
  }
  return s;
}

void print_job(const store::Job& j, const std::vector<store::JobEvent>& events) {
  const auto& s = j.spec;
  std::printf("%s  %s", j.id.c_str(), std::string(store::state_name(j.state)).c_str());
  if (!j.machine_id.empty()) std::printf(" on %s", j.machine_id.c_str());
  std::printf("  (attempt %u)\n", j.attempt);
  std::printf("  part      %s, material %s, tool %s\n", s.part_id().c_str(), s.material().c_str(),
              s.tool_id().c_str());
  std::printf("  cut       %g mm at %g mm/s, %g rpm; machine %s; priority %u\n", s.depth_mm(),
              s.feedrate_mm_s(), s.spindle_rpm(), or_any(s.machine_id()).c_str(), s.priority());
  std::printf("  submitted %s, updated %s\n", store::format_time(j.created_at_ms).c_str(),
              store::format_time(j.updated_at_ms).c_str());
  if (j.plan) {
    std::printf("  plan      %s: %s\n", std::string(store::variant_name(j.variant)).c_str(),
                j.explanation.c_str());
    const auto& prog = j.plan->program();
    std::string passes;
    for (const auto& p : prog.passes()) {
      char depth[32];
      std::snprintf(depth, sizeof depth, "%g mm", p.depth_mm());
      passes += (passes.empty() ? "" : ", ") + std::string(depth);
    }
    const auto& gcode = prog.gcode();
    const auto gcode_lines = std::count(gcode.begin(), gcode.end(), '\n');
    // The plan has no id of its own: each attempt runs it as
    // configuration <job>-a<attempt>, made at dispatch.
    const std::string conf =
        j.attempt > 0 ? "configuration '" + smc::cell::Planner::config_id(j, j.attempt) + "'"
                      : std::string("not dispatched yet");
    std::printf("            %s, %d passes%s%s; for %s\n", conf.c_str(), prog.passes_size(),
                passes.empty() ? "" : ": ", passes.c_str(),
                j.planned_for.empty() ? "any machine" : j.planned_for.c_str());
    if (gcode_lines > 0) {
      std::printf("            G-code: %ld lines (smc-cell job show %s --gcode)\n",
                  static_cast<long>(gcode_lines), j.id.c_str());
    }
  }
  if (j.result) {
    const auto& r = *j.result;
    // The cell records the peak F_Y against the highest reference the edge
    // held (overshoot_pct); the per-revolution violation is the edge's own.
    // The counts keep one form ("1 chatter events"): scripts read this line.
    char speed[64] = "";
    if (r.spindle_speed_changes() > 0) {
      std::snprintf(speed, sizeof speed, ", %u spindle speed changes", r.spindle_speed_changes());
    }
    char force[96] = "";
    if (r.force_reference_n() > 0) {
      std::snprintf(force, sizeof force, ", peak force %+.0f %% vs reference %.0f N",
                    r.overshoot_pct(), r.force_reference_n());
    }
    std::printf("  result    %s, %u/%u passes, %u rewrites%s, %u chatter events%s, cycle %.1f s\n",
                r.completed() ? "completed" : "not completed", r.passes_completed(),
                r.passes_planned(), r.program_rewrites(), speed, r.chatter_events(), force,
                r.cycle_time_s());
  }
  std::printf("  events\n");
  for (const auto& e : events) {
    const std::string from = e.from_state == smc::config::JOB_STATE_UNSPECIFIED
                                 ? std::string("(new)")
                                 : std::string(store::state_name(e.from_state));
    const std::string on = e.to_state == smc::config::JOB_ASSIGNED ? " [" + e.machine_id + "]" : "";
    if (e.is_note()) {  // the state did not change
      std::printf("    %2lld  %s  %-26s %s\n", static_cast<long long>(e.seq),
                  store::format_time(e.time_ms).c_str(), "(note)", e.reason.c_str());
      continue;
    }
    std::printf("    %2lld  %s  %-11s -> %-11s %s%s\n", static_cast<long long>(e.seq),
                store::format_time(e.time_ms).c_str(), from.c_str(),
                std::string(store::state_name(e.to_state)).c_str(), e.reason.c_str(), on.c_str());
  }
}

}  // namespace

namespace {

// The job with this id, or exit 2 naming the database and how to list ids.
store::Job known_job(store::Store& s, const std::string& id) {
  auto j = s.job(id);
  if (!j) {
    throw Failure(2, "unknown job '" + id + "' in " + s.path() +
                         "; fix: see the ids with 'smc-cell job list --db " + s.path() + "'");
  }
  return *j;
}

}  // namespace

SMC_CELL_COMMAND(job, 20) {
  auto* job = app.add_subcommand("job", "Jobs: submit a job file, list jobs, show one, cancel one");
  job->require_subcommand(1);

  struct SubmitArgs {
    std::string file;
    std::string db;
  };
  auto submit_args = std::make_shared<SubmitArgs>();
  auto* submit = job->add_subcommand(
      "submit",
      "Validate a job file (smc.config.Job as textproto or JSON) against the database and queue "
      "it. Durable on return; a running cell picks it up from the database. Exits 2 with "
      "file, field and fix for a bad job, writing nothing");
  submit->add_option("FILE", submit_args->file, "Job file, e.g. cell/jobs/transfer_line.textproto")
      ->required();
  add_db_option(submit, submit_args->db);
  submit->callback([submit_args] {
    store::Store s = store::Store::open(submit_args->db, store::OpenMode::kExisting);
    try {
      const store::Job j = store::submit_job_file(s, submit_args->file);
      std::printf("%s queued: part %s, %g mm at %g mm/s, %g rpm, machine %s\n", j.id.c_str(),
                  j.spec.part_id().c_str(), j.spec.depth_mm(), j.spec.feedrate_mm_s(),
                  j.spec.spindle_rpm(), or_any(j.spec.machine_id()).c_str());
    } catch (const store::JobFileError& e) {
      throw Failure(2, std::string(e.what()) + "\n" + submit_args->file +
                           ": job refused; nothing was written");
    }
  });

  struct ListArgs {
    std::string db;
    std::string state;
  };
  auto list_args = std::make_shared<ListArgs>();
  auto* list = job->add_subcommand("list", "Jobs in submission order");
  add_db_option(list, list_args->db);
  list->add_option("--state", list_args->state, "Only jobs in this state (" + all_states() + ")");
  list->callback([list_args] {
    store::JobFilter filter;
    if (!list_args->state.empty()) {
      filter.state = store::parse_state(list_args->state);
      if (!filter.state) {
        throw Failure(
            2, "--state '" + list_args->state + "': unknown state; use one of: " + all_states());
      }
    }
    store::Store s = store::Store::open(list_args->db, store::OpenMode::kExisting);
    const auto jobs = s.jobs(filter);
    std::printf("%-12s %-11s %-12s %-8s %-8s %-7s %s\n", "ID", "STATE", "PART", "MACHINE",
                "VARIANT", "ATTEMPT", "UPDATED");
    for (const auto& j : jobs) {
      std::printf("%-12s %-11s %-12s %-8s %-8s %-7u %s\n", j.id.c_str(),
                  std::string(store::state_name(j.state)).c_str(), j.spec.part_id().c_str(),
                  j.machine_id.empty() ? "-" : j.machine_id.c_str(),
                  j.variant == smc::config::SMC_UNSPECIFIED
                      ? "-"
                      : std::string(store::variant_name(j.variant)).c_str(),
                  j.attempt, store::format_time(j.updated_at_ms).c_str());
    }
    if (jobs.empty()) std::printf("(no jobs%s)\n", filter.state ? " in that state" : "");
  });

  struct ShowArgs {
    std::string id;
    std::string db;
    bool gcode = false;
    bool config = false;
  };
  auto show_args = std::make_shared<ShowArgs>();
  auto* show = job->add_subcommand(
      "show", "One job: its spec, state, plan (variant and why), result and every event");
  show->add_option("ID", show_args->id, "Job id, e.g. job-000001")->required();
  add_db_option(show, show_args->db);
  show->add_flag("--gcode", show_args->gcode,
                 "Print only the plan's G-code program (RS274NGC), e.g. to save it as a .ngc file");
  show->add_flag("--config", show_args->config,
                 "Print only the supervisor configuration as sent to its machine (text format),\n"
                 "e.g. to run it again with smc-edge simulate --config")
      ->excludes("--gcode");
  show->callback([show_args] {
    store::Store s = store::Store::open(show_args->db, store::OpenMode::kExisting);
    const store::Job j = known_job(s, show_args->id);
    if (show_args->config) {
      const auto m = j.machine_id.empty() ? std::nullopt : s.machine(j.machine_id);
      if (!j.plan || !m || j.attempt == 0) {
        throw Failure(1, j.id + " has not been sent to a machine yet (" +
                             std::string(store::state_name(j.state)) + " now)");
      }
      const auto structure = smc::cell::structure_model(s, j, m->id);
      std::fputs(
          smc::documents::to_textproto(smc::cell::Planner::for_machine(
                                           *j.plan, *m, smc::cell::Planner::config_id(j, j.attempt),
                                           structure ? &*structure : nullptr))
              .c_str(),
          stdout);
      return;
    }
    if (show_args->gcode) {
      if (!j.plan || j.plan->program().gcode().empty()) {
        throw Failure(1, j.id + " has no G-code yet: it is rendered when the job is planned (" +
                             std::string(store::state_name(j.state)) + " now)");
      }
      std::fputs(j.plan->program().gcode().c_str(), stdout);
      return;
    }
    print_job(j, s.events(j.id));
  });

  struct CancelArgs {
    std::string id;
    std::string db;
    std::string reason;
  };
  auto cancel_args = std::make_shared<CancelArgs>();
  auto* cancel = job->add_subcommand(
      "cancel",
      "Cancel a queued, planned or assigned job: it fails with the reason (an assigned one is "
      "interrupted first, and a running cell withdraws it from its mill). A running job is "
      "stopped at the mill (feed hold), not here");
  cancel->add_option("ID", cancel_args->id, "Job id, e.g. job-000001")->required();
  cancel->add_option("--reason", cancel_args->reason, "Why, for the job's history")->required();
  add_db_option(cancel, cancel_args->db);
  cancel->callback([cancel_args] {
    store::Store s = store::Store::open(cancel_args->db, store::OpenMode::kExisting);
    std::optional<store::Job> j = known_job(s, cancel_args->id);
    const std::string why = "cancelled: " + cancel_args->reason;
    if (j->state == smc::config::JOB_ASSIGNED) {
      if (!s.transition(j->id, j->state, smc::config::JOB_INTERRUPTED, why)) {
        throw Failure(1, j->id + " changed state meanwhile; look again with 'smc-cell job show'");
      }
      j = s.job(j->id);
    }
    if (j->state != smc::config::JOB_QUEUED && j->state != smc::config::JOB_PLANNED &&
        j->state != smc::config::JOB_INTERRUPTED) {
      throw Failure(2, j->id + " is " + std::string(store::state_name(j->state)) +
                           "; only queued, planned and assigned jobs can be cancelled");
    }
    if (!s.transition(j->id, j->state, smc::config::JOB_FAILED, why)) {
      throw Failure(1, j->id + " changed state meanwhile; look again with 'smc-cell job show'");
    }
    std::printf("%s cancelled (%s)\n", j->id.c_str(), cancel_args->reason.c_str());
  });
}
