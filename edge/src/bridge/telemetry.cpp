#include <spdlog/spdlog.h>

#include <algorithm>

#include "bridge.hpp"
#include "smc/supervision/gcode.hpp"

namespace smc::edge {

using smc::wire::set_string;
using namespace std::chrono_literals;

void EdgeService::Impl::drain() {
  if (!job) return;
  EdgeCore& c = *job->core;
  EdgeEvent e;
  FixedProgram prog;
  while (c.programs().try_pop(prog)) job->program = prog;
  while (c.events().try_pop(e)) on_event(e);
  // No rewrite follows when the configuration has no suppressor, or the
  // program is full: publish the event as it is.
  if (pending_chatter && std::chrono::steady_clock::now() - pending_since > 200ms) {
    chatter_writer.write(*pending_chatter);
    pending_chatter.reset();
  }
  RevolutionRecord r;
  while (c.revolutions().try_pop(r)) {
    job->latest = r;
    smc_data_ForceSummary s{};
    set_string(s.machine_id, opt.machine_id);
    s.machine_time_ns = machine_ns(r.t_s);
    s.revolution = r.revolution;
    s.pass_index = static_cast<uint16_t>(r.pass_index);
    s.pass_count = static_cast<uint16_t>(r.pass_count);
    s.f_y_peak_n = static_cast<float>(r.f_y_peak_n);
    s.f_ref_n = static_cast<float>(r.f_ref_n);
    s.feedrate_mm_s = static_cast<float>(r.feedrate_mm_s);
    s.feed_per_tooth_mm = static_cast<float>(r.feed_per_tooth_mm);
    s.depth_mm = static_cast<float>(r.depth_mm);
    s.spindle_rpm = static_cast<float>(r.spindle_rpm);
    s.spindle_power_w = static_cast<float>(r.power_mean_w);
    s.in_contact = r.contact;
    s.chatter = r.chatter;
    summary_writer.write(s);
    if (r.contact) job->peak_force_n = std::max(job->peak_force_n, r.f_y_peak_n);
  }
  ForceBatchRecord b;
  while (c.batches().try_pop(b)) {
    smc_data_ForceBatch fb{};
    set_string(fb.machine_id, opt.machine_id);
    fb.first_sample_time_ns = machine_ns(b.first_t_s);
    fb.sample_period_ns = static_cast<uint32_t>(b.period_s * 1e9);
    fb.decimation = static_cast<uint16_t>(opt.batch_decimation);
    fb.count = b.count;
    for (size_t i = 0; i < b.count; ++i) {
      fb.f_y_n[i] = b.f_y[i];
      fb.f_z_n[i] = b.f_z[i];
    }
    batch_writer.write(fb);
  }
}

void EdgeService::Impl::publish_program(const EdgeEvent& e) {
  // The core pushes the program before the event, so it is there now.
  FixedProgram latest;
  while (job->core->programs().try_pop(latest)) job->program = latest;
  smc::config::PartProgram prog = job->config.program();
  prog.clear_passes();
  const FixedProgram& fp = job->program;
  for (int i = 0; i < fp.count; ++i) {
    auto* p = prog.add_passes();
    p->set_depth_mm(fp.passes[static_cast<size_t>(i)].depth_mm);
    p->set_feedrate_mm_s(fp.passes[static_cast<size_t>(i)].feedrate_mm_s);
    p->set_spindle_rpm(fp.passes[static_cast<size_t>(i)].spindle_rpm);
  }
  prog.set_revision(fp.revision);
  // The program a CNC control would be given now: the remaining depth
  // from the pass the rewrite restarts (services/supervision gcode.hpp).
  prog.clear_gcode();
  try {
    smc::config::SupervisorConfig now = job->config;
    *now.mutable_program() = prog;
    const int from =
        std::clamp(static_cast<int>(e.pass_index), 0, std::max(0, static_cast<int>(fp.count) - 1));
    prog.set_gcode(smc::supervision::render_gcode(
        now, {.title = "job " + job->assignment.job_id() + " on " + opt.machine_id + ", rewrite " +
                       std::to_string(fp.revision) + ": passes " + std::to_string(from + 1) +
                       " to " + std::to_string(fp.count),
              .first_pass = from}));
  } catch (const std::exception& ex) {
    spdlog::warn("{}: the rewritten program has no G-code: {}", opt.machine_id, ex.what());
  }
  program_writer.publish(opt.machine_id, job->assignment.job_id(), prog);
}

void EdgeService::Impl::on_event(const EdgeEvent& e) {
  switch (e.kind) {
    case EventKind::kSituationChanged: {
      smc_data_SupervisorSituation s{};
      set_string(s.machine_id, opt.machine_id);
      s.machine_time_ns = machine_ns(e.t_s);
      s.sequence_number = ++situation_seq;
      s.active_steps = e.active_steps;
      s.modules_active = e.active;
      s.inputs = e.inputs;
      set_string(s.config_id, job->config.config_id());
      situation_writer.write(s);
      const bool hold = (e.active & bit(ModuleId::C)) != 0;
      if (hold && state == smc_data_EDGE_RUNNING) set_state(smc_data_EDGE_FEED_HOLD, "feed hold");
      if (!hold && state == smc_data_EDGE_FEED_HOLD)
        set_state(smc_data_EDGE_RUNNING, "running job " + job->assignment.job_id());
      break;
    }
    case EventKind::kChatterDetected:
    case EventKind::kChatterSignalled: {
      // Published once the suppressor has rewritten the program (next
      // fast period), so that it carries the new pass count.
      smc_data_ChatterEvent& ce = pending_chatter.emplace();
      set_string(ce.machine_id, opt.machine_id);
      ce.event_id = chatter_id_base + ++chatter_seq;
      ce.machine_time_ns = machine_ns(e.t_s);
      ce.source = e.kind == EventKind::kChatterDetected ? smc_data_CHATTER_AUTOMATIC
                                                        : smc_data_CHATTER_OPERATOR;
      ce.frequency_hz = static_cast<float>(e.frequency_hz);
      ce.energy_ratio = static_cast<float>(e.ratio);
      ce.pass_index = static_cast<uint16_t>(e.pass_index);
      ce.new_pass_count = static_cast<uint16_t>(e.pass_count);
      set_string(ce.job_id, job->assignment.job_id());
      pending_since = std::chrono::steady_clock::now();
      ++job->chatter_events;
      break;
    }
    case EventKind::kProgramRewritten:
    case EventKind::kSpeedChanged: {
      const bool speed = e.kind == EventKind::kSpeedChanged;
      ++(speed ? job->spindle_speed_changes : job->program_rewrites);
      publish_program(e);
      if (pending_chatter) {
        pending_chatter->new_pass_count = static_cast<uint16_t>(job->program.count);
        if (speed) pending_chatter->new_spindle_rpm = static_cast<float>(e.value);
        chatter_writer.write(*pending_chatter);
        pending_chatter.reset();
      }
      if (speed) {
        const std::string what = fmt::format(
            "spindle speed changed to {:.0f} rpm (chatter at {:.0f} Hz)", e.value, e.frequency_hz);
        spdlog::warn("{}: {}", opt.machine_id, what);
        publish_progress(smc_data_JOB_RUNNING, what);
      } else {
        spdlog::warn("{}: chatter suppressor rewrote the program to {} passes", opt.machine_id,
                     job->program.count);
        publish_progress(smc_data_JOB_RUNNING,
                         "program rewritten to " + std::to_string(job->program.count) + " passes");
      }
      break;
    }
    case EventKind::kToolBroken: {
      // The supervisor holds the feed (SMC II+, step 9); the job ends here
      // and the cell hears why.
      job->failure = fmt::format(
          "tool breakage at {:.3f} s in pass {}: tooth window {} lost {:.0f} % of the mean "
          "window force to the next; feed held{}",
          e.t_s, e.pass_index + 1, e.module + 1, 100.0 * e.value,
          e.ratio > 0 ? ", tool retracted"
                      : " (this drive cannot retract: clear the tool by hand)");
      spdlog::error("{}: {}", opt.machine_id, job->failure);
      break;
    }
    case EventKind::kFault: {
      std::string why = std::string("fault hold: ") + to_string(e.fault);
      if (e.module >= 0)
        why += " in module " + std::string(1, letter(static_cast<ModuleId>(e.module)));
      if (e.why != nullptr) why += std::string(": ") + e.why;
      set_state(smc_data_EDGE_FAULT, why);
      break;
    }
    case EventKind::kFaultCleared:
      set_state(smc_data_EDGE_RUNNING, "fault cleared by the operator");
      break;
    case EventKind::kPassStarted:
    case EventKind::kPassCompleted:
      publish_progress(smc_data_JOB_RUNNING,
                       std::string(to_string(e.kind)) + " " + std::to_string(e.pass_index + 1));
      break;
    case EventKind::kProgramDone:
      job->done = true;
      break;
  }
}

}  // namespace smc::edge
