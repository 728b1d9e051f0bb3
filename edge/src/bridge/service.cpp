#include "smc/edge/service.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "smc/common/clock.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/realtime.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/transport/document.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace tr = smc::transport;
using smc::wire::get_string;
using smc::wire::set_string;
using namespace std::chrono_literals;

namespace {

int64_t unix_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

uint64_t machine_ns(double t_s) { return static_cast<uint64_t>(t_s * 1e9); }

const tr::Schema kConfigSchema{"smc.config.SupervisorConfig", smc::config::SCHEMA_VERSION_CURRENT};
const tr::Schema kJobSchema{"smc.config.JobAssignment", smc::config::SCHEMA_VERSION_CURRENT};
const tr::Schema kProgramSchema{"smc.config.PartProgram", smc::config::SCHEMA_VERSION_CURRENT};

// A job in the loop: the core, its mill and the real-time thread.
struct RunningJob {
  ~RunningJob() {
    if (pacer.joinable()) {
      stop_pacer = true;
      pacer.join();
    }
  }
  // Paced mode (--speedup other than 1): a plain thread ticks the core so
  // that machine time runs `speedup` times faster than the wall clock. There
  // is no machine to protect in an accelerated simulation, so a late tick is
  // simply caught up, not an overrun.
  std::thread pacer;
  std::atomic<bool> stop_pacer{false};
  std::atomic<bool> paced_done{false};
  smc::config::JobAssignment assignment;
  smc::config::SupervisorConfig config;
  std::unique_ptr<SimulatedMill> mill;
  std::unique_ptr<EdgeCore> core;
  std::unique_ptr<RealTimeEdge> rt;
  // What the comms thread knows of the loop, only from the core's rings (the
  // core itself belongs to the loop thread).
  RevolutionRecord latest{};
  FixedProgram program;
  bool done = false;
  uint32_t sequence = 0;
  uint32_t chatter_events = 0;
  double peak_force_n = 0;
  std::chrono::steady_clock::time_point last_progress{};
};

}  // namespace

struct EdgeService::Impl {
  ServiceOptions opt;
  RealClock clock;
  tr::Participant participant;
  // Inputs.
  tr::Topic<smc_data_Envelope> config_topic, job_topic;
  tr::DocumentReader<smc::config::SupervisorConfig> config_reader;
  tr::DocumentReader<smc::config::JobAssignment> job_reader;
  tr::Topic<smc_data_OperatorCommand> command_topic;
  tr::Reader<smc_data_OperatorCommand> command_reader;
  // Outputs.
  tr::Topic<smc_data_ForceSummary> summary_topic;
  tr::Writer<smc_data_ForceSummary> summary_writer;
  tr::Topic<smc_data_ForceBatch> batch_topic;
  tr::Writer<smc_data_ForceBatch> batch_writer;
  tr::Topic<smc_data_ChatterEvent> chatter_topic;
  tr::Writer<smc_data_ChatterEvent> chatter_writer;
  tr::Topic<smc_data_SupervisorSituation> situation_topic;
  tr::Writer<smc_data_SupervisorSituation> situation_writer;
  tr::Topic<smc_data_EdgeStatus> status_topic;
  tr::Writer<smc_data_EdgeStatus> status_writer;
  tr::Topic<smc_data_JobProgress> progress_topic;
  tr::Writer<smc_data_JobProgress> progress_writer;
  tr::Topic<smc_data_Envelope> program_topic;
  tr::DocumentWriter program_writer;
  tr::WaitSet waitset;

  // State.
  std::optional<smc::config::SupervisorConfig> config;   // in force
  std::optional<smc::config::SupervisorConfig> pending;  // accepted during a job
  std::optional<smc::config::JobAssignment> waiting;     // assignment waiting for its config
  std::set<std::string> started;                         // "job#attempt" started (journal included)
  std::set<std::string> journalled;                      // of those, started by an earlier run
  std::set<std::string> reported;                        // earlier runs' jobs reported interrupted
  std::unique_ptr<RunningJob> job;
  OperatorInputs operator_inputs;
  smc_data_EdgeState state = smc_data_EDGE_IDLE;
  std::string message = "waiting for a configuration";
  uint64_t chatter_id_base = static_cast<uint64_t>(unix_ns() / 1000);  // survives restarts
  uint64_t chatter_seq = 0;
  uint32_t situation_seq = 0;
  std::optional<smc_data_ChatterEvent> pending_chatter;
  std::chrono::steady_clock::time_point pending_since{};
  std::chrono::steady_clock::time_point last_status{};

  explicit Impl(ServiceOptions o)
      : opt(std::move(o)),
        participant({.domain_id = opt.domain_id, .partition = opt.partition}),
        config_topic(participant, smc::wire::kConfigTopic),
        job_topic(participant, smc::wire::kJobTopic),
        config_reader(config_topic, kConfigSchema),
        job_reader(job_topic, kJobSchema),
        command_topic(participant),
        command_reader(command_topic),
        summary_topic(participant),
        summary_writer(summary_topic),
        batch_topic(participant),
        batch_writer(batch_topic),
        chatter_topic(participant),
        chatter_writer(chatter_topic),
        situation_topic(participant),
        situation_writer(situation_topic),
        status_topic(participant),
        status_writer(status_topic, status_topic.qos().with_lease(opt.lease)),
        progress_topic(participant),
        progress_writer(progress_topic),
        program_topic(participant, smc::wire::kProgramTopic),
        program_writer(program_topic, kProgramSchema),
        waitset(participant) {
    load_journal();
    waitset.attach(config_reader.reader(), 1);
    waitset.attach(job_reader.reader(), 2);
    waitset.attach(command_reader, 3);
  }

  // ----------------------------------------------------------- journal --

  void load_journal() {
    if (opt.state_file.empty()) return;
    std::FILE* f = std::fopen(opt.state_file.c_str(), "r");
    if (f == nullptr) return;  // first run
    char line[256];
    while (std::fgets(line, sizeof line, f) != nullptr) {
      std::string tag(line);
      while (!tag.empty() && (tag.back() == '\n' || tag.back() == '\r')) tag.pop_back();
      if (tag.empty()) continue;
      started.insert(tag);
      journalled.insert(tag);
    }
    std::fclose(f);
    spdlog::info("{}: journal {}: {} job attempt(s) started by earlier runs", opt.machine_id,
                 opt.state_file, journalled.size());
  }

  // Durable before the job starts: a crash right after must not lose it.
  void journal(const std::string& tag) {
    if (opt.state_file.empty()) return;
    std::FILE* f = std::fopen(opt.state_file.c_str(), "a");
    if (f == nullptr) {
      throw std::runtime_error(opt.state_file + ": cannot append to the edge's journal");
    }
    std::fprintf(f, "%s\n", tag.c_str());
    std::fflush(f);
    ::fsync(::fileno(f));
    std::fclose(f);
  }

  // ------------------------------------------------------------ status --

  void publish_status() {
    smc_data_EdgeStatus st{};
    set_string(st.machine_id, opt.machine_id);
    st.machine_time_ns = job ? machine_ns(job->latest.t_s) : 0;
    st.state = state;
    set_string(st.config_id, config ? config->config_id() : "");
    set_string(st.job_id, job ? job->assignment.job_id() : "");
    if (job) {
      st.loop_overruns = job->rt->loop().overruns();
      st.loop_latency_p99_us =
          static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                    job->rt->loop().latency().percentile(0.99))
                                    .count());
    }
    set_string(st.message, message);
    status_writer.write(st);
    last_status = std::chrono::steady_clock::now();
  }

  void set_state(smc_data_EdgeState s, std::string why) {
    state = s;
    message = std::move(why);
    spdlog::info("{}: {}", opt.machine_id, message);
    publish_status();
  }

  // ------------------------------------------------------ configuration --

  // The mill's own model (--mill-model) machines the job's part: the
  // configuration's cutter and part geometry, the mill's cutting law and
  // structure. Without --mill-model the configuration's model is used.
  void use_mill_model(smc::config::SupervisorConfig& cfg) const {
    if (opt.mill_model_file.empty()) return;
    smc::config::MillingModel own;
    smc::documents::load(opt.mill_model_file, own);
    if (cfg.milling_model().has_cutter()) *own.mutable_cutter() = cfg.milling_model().cutter();
    if (cfg.milling_model().has_workpiece())
      *own.mutable_workpiece() = cfg.milling_model().workpiece();
    *cfg.mutable_milling_model() = own;
  }

  // Full check: everything the job would build, built now.
  std::string check(smc::config::SupervisorConfig& cfg) {
    if (cfg.machine().machine_id() != opt.machine_id) {
      return "supervisor_config.machine.machine_id: '" + cfg.machine().machine_id() +
             "' is not this edge ('" + opt.machine_id + "')";
    }
    try {
      EdgeConfig ec = edge_config_from_proto(cfg);
      use_mill_model(cfg);
      SimulatedMill probe(cfg.milling_model(), cfg.simulation(), ec.params.sample_period_s);
    } catch (const std::exception& e) {
      return e.what();
    }
    return {};
  }

  void take_configs() {
    config_reader.take(
        [&](const std::string& key, const smc::config::SupervisorConfig& doc) {
          if (key != opt.machine_id) return;
          smc::config::SupervisorConfig cfg = doc;
          const std::string why = check(cfg);
          if (!why.empty()) {
            spdlog::error("{}: configuration '{}' rejected: {}", opt.machine_id, cfg.config_id(),
                          why);
            message = "configuration '" + cfg.config_id() + "' rejected: " + why.substr(0, 90);
            publish_status();
            return;
          }
          if (job) {
            pending = cfg;
            spdlog::info("{}: configuration '{}' accepted; in force after job {}", opt.machine_id,
                         cfg.config_id(), job->assignment.job_id());
            return;
          }
          config = cfg;
          set_state(smc_data_EDGE_CONFIGURED, "configuration '" + cfg.config_id() + "' in force");
        },
        [&](const tr::DocumentError& e) {
          if (e.key != opt.machine_id) return;
          spdlog::error("{}: configuration rejected: {}", opt.machine_id, e.message);
          message = std::string("configuration rejected (") + tr::to_string(e.fault) +
                    "): " + e.message.substr(0, 80);
          publish_status();
        });
  }

  // --------------------------------------------------------------- jobs --

  void take_jobs() {
    job_reader.take(
        [&](const std::string& key, const smc::config::JobAssignment& a) {
          if (key != opt.machine_id) return;
          if (a.job_id().empty()) {  // the cell withdrew the assignment
            waiting.reset();
            return;
          }
          waiting = a;
        },
        [&](const tr::DocumentError& e) {
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

  void start_job(const smc::config::JobAssignment& a) {
    auto j = std::make_unique<RunningJob>();
    j->assignment = a;
    j->config = *config;  // already carries the mill's model (check())
    EdgeConfig ec = edge_config_from_proto(j->config);
    j->mill = std::make_unique<SimulatedMill>(j->config.milling_model(), j->config.simulation(),
                                              ec.params.sample_period_s);
    j->core = std::make_unique<EdgeCore>(ec, *j->mill);
    j->core->set_batch_decimation(opt.batch_decimation);
    j->core->start();
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
    const std::string tag = a.job_id() + "#" + std::to_string(a.attempt());
    journal(tag);
    started.insert(tag);
    job = std::move(j);
    operator_inputs = OperatorInputs{};
    job->rt->push_operator_inputs(operator_inputs);
    if (!paced()) {
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

  void report_interrupted(const std::string& job_id, const std::string& why) {
    smc_data_JobProgress p{};
    set_string(p.machine_id, opt.machine_id);
    set_string(p.job_id, job_id);
    p.phase = smc_data_JOB_INTERRUPTED;
    set_string(p.message, why);
    progress_writer.write(p);
    spdlog::warn("{}: job {} was started by an earlier run of this edge: reported interrupted",
                 opt.machine_id, job_id);
  }

  void publish_progress(smc_data_JobPhase phase, const std::string& why) {
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
    p.peak_force_n = static_cast<float>(job->peak_force_n);
    set_string(p.message, why);
    progress_writer.write(p);
    job->last_progress = std::chrono::steady_clock::now();
  }

  bool paced() const { return opt.paced || opt.speedup != 1.0; }

  bool job_running() const {
    return !paced() ? job->rt->loop().running() : !job->paced_done.load();
  }

  void stop_loop() {
    if (job->pacer.joinable()) {
      job->stop_pacer = true;
      job->pacer.join();
    }
    job->rt->stop();
  }

  void finish_job() {
    stop_loop();
    drain();                                     // whatever the loop produced last
    job->done = job->done || job->core->done();  // the loop has stopped: safe to look
    if (pending_chatter) {
      chatter_writer.write(*pending_chatter);
      pending_chatter.reset();
    }
    const bool ok = job->done;
    publish_progress(ok ? smc_data_JOB_DONE : smc_data_JOB_FAILED,
                     ok ? "program complete" : "stopped before the end");
    spdlog::info("{}: job {} {}", opt.machine_id, job->assignment.job_id(), ok ? "done" : "failed");
    job.reset();
    if (pending) {
      config = *pending;
      pending.reset();
    }
    set_state(config ? smc_data_EDGE_CONFIGURED : smc_data_EDGE_IDLE,
              config ? "configuration '" + config->config_id() + "' in force" : "idle");
  }

  // ---------------------------------------------------------- operator --

  void take_commands() {
    bool changed = false;
    command_reader.take([&](const smc_data_OperatorCommand& c, const tr::SampleInfo& info) {
      if (!info.valid_data || get_string(c.machine_id) != opt.machine_id) return;
      const std::string who = get_string(c.operator_name);
      switch (c.action) {
        case smc_data_OP_FEED_HOLD_ON:
          operator_inputs.feed_hold = true;
          break;
        case smc_data_OP_FEED_HOLD_OFF:
          operator_inputs.feed_hold = false;
          ++operator_inputs.releases;
          break;
        case smc_data_OP_CHATTER_SIGNAL:
          ++operator_inputs.chatter_signals;
          break;
      }
      spdlog::info("{}: operator command {} from '{}' (id {})", opt.machine_id,
                   c.action == smc_data_OP_FEED_HOLD_ON    ? "feed hold on"
                   : c.action == smc_data_OP_FEED_HOLD_OFF ? "feed hold off"
                                                           : "chatter signal",
                   who, c.command_id);
      changed = true;
    });
    if (changed && job) job->rt->push_operator_inputs(operator_inputs);
  }

  // ---------------------------------------------------------- telemetry --

  void drain() {
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

  void on_event(const EdgeEvent& e) {
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
      case EventKind::kProgramRewritten: {
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
        program_writer.publish(opt.machine_id, job->assignment.job_id(), prog);
        if (pending_chatter) {
          pending_chatter->new_pass_count = fp.count;
          chatter_writer.write(*pending_chatter);
          pending_chatter.reset();
        }
        spdlog::warn("{}: chatter suppressor rewrote the program to {} passes", opt.machine_id,
                     fp.count);
        publish_progress(smc_data_JOB_RUNNING,
                         "program rewritten to " + std::to_string(fp.count) + " passes");
        break;
      }
      case EventKind::kFault: {
        std::string why = std::string("fault hold: ") + to_string(e.fault);
        if (e.module >= 0) why += std::string(" in module ") + static_cast<char>('A' + e.module);
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

  int run(const std::atomic<bool>& stop) {
    publish_status();
    std::vector<int64_t> fired;
    while (!stop.load()) {
      waitset.wait(10ms, fired);
      take_configs();
      take_commands();
      take_jobs();
      drain();
      if (job) {
        if (job->done || !job_running()) {
          finish_job();
        } else if (std::chrono::steady_clock::now() - job->last_progress > 1s) {
          publish_progress(smc_data_JOB_RUNNING, "running");
        }
      }
      if (std::chrono::steady_clock::now() - last_status > 1s) publish_status();
    }
    if (job) {
      stop_loop();
      drain();
      publish_progress(smc_data_JOB_INTERRUPTED, "edge stopped");
      job.reset();
    }
    return 0;
  }
};

EdgeService::EdgeService(ServiceOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}
EdgeService::~EdgeService() = default;
int EdgeService::run(const std::atomic<bool>& stop) { return impl_->run(stop); }

}  // namespace smc::edge
