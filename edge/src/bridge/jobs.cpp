#include <spdlog/spdlog.h>

#include <algorithm>

#include "bridge.hpp"

namespace smc::edge {

using smc::wire::set_string;

void EdgeService::Impl::take_jobs() {
  job_reader.take(
      [&](const std::string& key, const smc::config::JobAssignment& a) {
        if (key != opt.machine_id) return;
        if (a.job_id().empty()) {  // the cell withdrew the assignment
          waiting.reset();
          return;
        }
        waiting = a;
      },
      [&](const tr::EnvelopeRejection& e) {
        if (e.key == opt.machine_id)
          spdlog::error("{}: assignment rejected: {}", opt.machine_id, e.message);
      });
  if (!waiting || job) return;
  const std::string tag = waiting->job_id() + "#" + std::to_string(waiting->attempt());
  if (started.count(tag)) {
    // Started by an earlier run of this edge (it crashed or was restarted
    // mid-job): the part is half cut, so the job is not run again; the cell
    // hears it was interrupted and re-queues it under its policy.
    if (journalled.count(tag) && reported.insert(tag).second) {
      report_interrupted(waiting->job_id(), "edge restarted during this attempt");
    }
    waiting.reset();
    return;
  }
  if (!config || config->config_id() != waiting->config_id()) return;  // wait for it
  start_job(*waiting);
  waiting.reset();
}

void EdgeService::Impl::start_job(const smc::config::JobAssignment& a) {
  auto j = std::make_unique<RunningJob>();
  j->assignment = a;
  j->config = *config;  // the cell's models: the simulated mill's own is its alone
  EdgeConfig ec = edge_config_from_proto(j->config);
  const std::string tag = a.job_id() + "#" + std::to_string(a.attempt());
  try {
    if (opt.drive == "linuxcnc") {
      LinuxCncDriveOptions lo;
      lo.machine_id = opt.machine_id;
      lo.program_dir = opt.program_dir;
      auto d = std::make_unique<LinuxCncDrive>(j->config, ec.params.sample_period_s, lo);
      j->cnc = d.get();
      j->mill = std::move(d);
    } else {
      j->mill = simulated_mill(j->config, ec.params.sample_period_s);
    }
    j->core = std::make_unique<EdgeCore>(ec, *j->mill);
    j->core->set_batch_decimation(opt.batch_decimation);
    j->core->start();  // the drive's load(): LinuxCNC checks and opens the program
  } catch (const std::exception& e) {
    // Nothing ran: the cell hears why, and the assignment is not taken again.
    journal(tag);
    started.insert(tag);
    smc_data_JobProgress p{};
    set_string(p.machine_id, opt.machine_id);
    set_string(p.job_id, a.job_id());
    p.phase = smc_data_JOB_FAILED;
    set_string(p.message, std::string("the machine cannot run it: ") + e.what());
    progress_writer.write(p);
    spdlog::error("{}: job {} not started: {}", opt.machine_id, a.job_id(), e.what());
    return;
  }
  j->program = ec.program;
  rt::RtOptions ro;
  ro.period = std::chrono::nanoseconds(
      static_cast<int64_t>(ec.params.sample_period_s * 1e9 / std::max(opt.speedup, 1e-3)));
  if (!opt.realtime) {
    ro.priority = 0;
    ro.lock_memory = false;
  }
  ro.overrun_threshold = opt.overrun_threshold;
  j->rt = std::make_unique<RealTimeEdge>(*j->core, ro, clock);
  journal(tag);
  started.insert(tag);
  job = std::move(j);
  operator_inputs = OperatorInputs{};
  job->rt->push_operator_inputs(operator_inputs);
  if (job->cnc != nullptr) {
    // LinuxCNC's servo thread paces the loop: one tick per servo record (a
    // tick without one is the drive's stale-record fault).
    RunningJob* rj = job.get();
    rj->pacer = std::thread([rj] {
      rt::TickInfo info{};
      while (!rj->stop_pacer && !rj->core->done()) {
        (void)rj->cnc->wait_sample();
        rj->rt->tick(info);
        ++info.index;
      }
      rj->paced_done = true;
    });
    spdlog::info("{}: job {} on LinuxCNC, paced by its servo thread", opt.machine_id, a.job_id());
  } else if (!paced()) {
    job->rt->start();
    spdlog::info("{}: real-time set-up: {}", opt.machine_id,
                 rt::summary(job->rt->setup_report(), ro));
  } else {
    RunningJob* rj = job.get();
    const auto period = ro.period;
    rj->pacer = std::thread([rj, period] {
      RealClock c;
      Nanos next = c.now();
      rt::TickInfo info{};
      while (!rj->stop_pacer && !rj->core->done()) {
        rj->rt->tick(info);
        ++info.index;
        next += period;
        if (c.now() < next) c.sleep_until(next);
      }
      rj->paced_done = true;
    });
    spdlog::info("{}: paced simulation at {}x real time (no real-time deadlines)", opt.machine_id,
                 opt.speedup);
  }
  set_state(smc_data_EDGE_RUNNING, "running job " + a.job_id());
  publish_progress(smc_data_JOB_RUNNING, "started");
}

void EdgeService::Impl::report_interrupted(const std::string& job_id, const std::string& why) {
  smc_data_JobProgress p{};
  set_string(p.machine_id, opt.machine_id);
  set_string(p.job_id, job_id);
  p.phase = smc_data_JOB_INTERRUPTED;
  set_string(p.message, why);
  progress_writer.write(p);
  spdlog::warn("{}: job {} was started by an earlier run of this edge: reported interrupted",
               opt.machine_id, job_id);
}

void EdgeService::Impl::publish_progress(smc_data_JobPhase phase, const std::string& why) {
  if (!job) return;
  const FixedProgram& prog = job->program;
  smc_data_JobProgress p{};
  set_string(p.machine_id, opt.machine_id);
  set_string(p.job_id, job->assignment.job_id());
  p.machine_time_ns = machine_ns(job->latest.t_s);
  p.sequence_number = ++job->sequence;
  p.phase = phase;
  p.pass_index = static_cast<uint16_t>(job->latest.pass_index);
  p.pass_count = prog.count;
  const double total = prog.total_depth_mm();
  const int pass = job->latest.pass_index;
  p.depth_removed_mm = static_cast<float>(job->done ? total : prog.depth_before(pass));
  p.fraction_done =
      static_cast<float>(total > 0 ? static_cast<double>(p.depth_removed_mm) / total : 0.0);
  p.chatter_events = job->chatter_events;
  p.program_rewrites = job->program_rewrites;
  p.spindle_speed_changes = job->spindle_speed_changes;
  p.peak_force_n = static_cast<float>(job->peak_force_n);
  set_string(p.message, why);
  progress_writer.write(p);
  job->last_progress = std::chrono::steady_clock::now();
}

bool EdgeService::Impl::job_running() const {
  // The edge ended the job itself (a tool breakage).
  if (!job->failure.empty()) return false;
  if (job->cnc != nullptr) {
    // A LinuxCNC fault ends the job: the drive holds the feed and LinuxCNC's
    // program is aborted; the cell hears why.
    if (job->failure.empty()) job->failure = job->cnc->fault();
    return job->failure.empty() && !job->paced_done.load();
  }
  return !paced() ? job->rt->loop().running() : !job->paced_done.load();
}

void EdgeService::Impl::stop_loop() {
  if (job->pacer.joinable()) {
    job->stop_pacer = true;
    job->pacer.join();
  }
  job->rt->stop();
}

void EdgeService::Impl::finish_job() {
  stop_loop();
  drain();                                     // whatever the loop produced last
  job->done = job->done || job->core->done();  // the loop has stopped: safe to look
  // The machine time the job ended at is the core's last sample, not the
  // last revolution telemetry carried (up to a revolution before it).
  job->latest.t_s = std::max(job->latest.t_s, job->core->drive_sample().force.t_s);
  job->peak_force_n = std::max(job->peak_force_n, job->core->peak_force_n());
  if (pending_chatter) {
    chatter_writer.write(*pending_chatter);
    pending_chatter.reset();
  }
  const bool ok = job->done;
  if (!ok && job->failure.empty() && job->cnc != nullptr) job->failure = job->cnc->fault();
  if (job->cnc != nullptr) {
    spdlog::info("{}: LinuxCNC servo records: {} read, {} lost, {} repeated", opt.machine_id,
                 job->cnc->samples(), job->cnc->lost_samples(), job->cnc->repeated_samples());
  }
  publish_progress(
      ok ? smc_data_JOB_DONE : smc_data_JOB_FAILED,
      ok ? "program complete" : (job->failure.empty() ? "stopped before the end" : job->failure));
  spdlog::info("{}: job {} {}", opt.machine_id, job->assignment.job_id(), ok ? "done" : "failed");
  job.reset();
  if (pending) {
    config = *pending;
    pending.reset();
  }
  set_state(config ? smc_data_EDGE_CONFIGURED : smc_data_EDGE_IDLE,
            config ? "configuration '" + config->config_id() + "' in force" : "idle");
}

}  // namespace smc::edge
