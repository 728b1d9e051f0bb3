#include "smc/cell/service.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include "smc/cell/candidates.hpp"
#include "smc/cell/channel_notes.hpp"
#include "smc/cell/dispatch.hpp"
#include "smc/cell/learning.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/store/catalog_docs.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/common/clock.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/force_process.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/supervision/config.hpp"
#include "smc/transport/dispatcher.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/documents.hpp"
#include "smc/wire/limits.hpp"
#include "smc/wire/topics.hpp"

namespace smc::cell {

namespace tr = smc::transport;
namespace cfg = smc::config;
using smc::wire::get_string;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

// "<job>-a<attempt>" must fit the wire's config id (and the job id its key).
static_assert(store::kMaxJobIdLength + 12 <= smc::wire::kConfigIdMax);
static_assert(store::kMaxJobIdLength <= smc::wire::kDocumentKeyMax);

std::string config_id_for(const store::Job& j, uint32_t attempt) {
  return Planner::config_id(j, attempt);
}

// One cell per database: an exclusive lock on "<db>.lock", held for the
// service's life. The kernel releases it when the process ends, however it
// ends, so a crash never leaves a stale lock behind.
class DatabaseLock {
 public:
  explicit DatabaseLock(const std::string& db_path) : path_(db_path + ".lock") {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) {
      throw store::StoreError(path_ + ": cannot open the cell's lock file (" +
                              std::strerror(errno) + ")");
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char holder[32] = {};
      const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
      ::close(fd_);
      std::string pid = n > 0 ? std::string(holder, static_cast<size_t>(n)) : "";
      while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
      throw store::StoreError(db_path + ": another smc-cell serve" +
                              (pid.empty() ? "" : " (pid " + pid + ")") +
                              " is using this database; fix: stop it first, or give this one "
                              "another --db");
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, pid.data(), pid.size(), 0);
  }
  ~DatabaseLock() { ::close(fd_); }
  DatabaseLock(const DatabaseLock&) = delete;
  DatabaseLock& operator=(const DatabaseLock&) = delete;

 private:
  std::string path_;
  int fd_ = -1;
};

struct Mill {
  bool alive = false;
  bool seen = false;
  smc_data_EdgeState state = smc_data_EDGE_IDLE;
  Clock::time_point lost_since = Clock::now();
};

struct Progress {
  uint32_t pass_index = 0, pass_count = 0, chatter = 0;
  double fraction = 0;
  float peak_force = 0;
};

}  // namespace

// Notices that the whole process was frozen (SIGSTOP, a paused container, a
// debugger): a thread that wakes every 100 ms keeps the longest gap between
// its wake-ups. A slow database call or plan does not stop it, and neither
// stops Cyclone DDS's own threads, which keep the participant's lease.
class FreezeWatch {
 public:
  FreezeWatch() : thread_([this] { watch(); }) {}
  ~FreezeWatch() {
    {
      std::lock_guard lock(mu_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  FreezeWatch(const FreezeWatch&) = delete;
  FreezeWatch& operator=(const FreezeWatch&) = delete;

  // The longest gap since the last call.
  std::chrono::nanoseconds take_longest() { return std::chrono::nanoseconds(longest_.exchange(0)); }

 private:
  void watch() {
    std::unique_lock lock(mu_);
    auto last = Clock::now();
    while (!cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return done_; })) {
      const auto now = Clock::now();
      const std::int64_t gap = (now - last).count();
      std::int64_t seen = longest_.load();
      while (gap > seen && !longest_.compare_exchange_weak(seen, gap)) {
      }
      last = now;
    }
  }
  std::mutex mu_;
  std::condition_variable cv_;
  bool done_ = false;
  std::atomic<std::int64_t> longest_{0};
  std::thread thread_;  // last: it starts once the members it uses exist
};

struct CellService::Impl {
  ServiceOptions opt;
  DatabaseLock lock;  // before the database is opened
  store::Store db;
  Planner planner;
  tr::Participant participant;
  smc::wire::DocumentPublisher<cfg::SupervisorConfig> config_writer;
  smc::wire::DocumentPublisher<cfg::JobAssignment> job_writer;
  smc::wire::DocumentPublisher<cfg::JobStatus> status_doc_writer;
  smc::wire::DocumentPublisher<cfg::CatalogView> catalog_writer;
  std::string catalog_sent;  // the last CatalogView published (serialized, without its time)
  tr::Topic<smc_data_EdgeStatus> edge_topic;
  tr::Reader<smc_data_EdgeStatus> edge_reader;
  tr::Topic<smc_data_JobProgress> progress_topic;
  tr::Reader<smc_data_JobProgress> progress_reader;
  tr::Topic<smc_data_ForceSummary> summary_topic;
  tr::Reader<smc_data_ForceSummary> summary_reader;
  tr::Topic<smc_data_ChatterEvent> chatter_topic;
  tr::Reader<smc_data_ChatterEvent> chatter_reader;
  smc::wire::DocumentSubscriber<cfg::PartProgram> program_reader;
  tr::Dispatcher dispatcher;
  // Job history: revolutions received and not yet written, by job id
  // (written in one transaction about twice a second and when the job ends).
  std::map<std::string, std::vector<store::JobRevolution>> history;
  // The job whose history a mill's summaries and programs belong to: its
  // last job, until another starts (the edge drains its last revolutions
  // after it reports the job's end).
  std::map<std::string, std::string> recording;  // machine -> job
  Clock::time_point history_flushed = Clock::now();

  std::map<std::string, Mill> mills;
  std::map<std::string, Progress> progress;                             // by job id
  std::map<std::string, std::vector<machining::ForceSample>> learning;  // by job id
  LearningPolicy policy;
  // Stability evidence: per machine its latest revolution and the job it
  // cuts; per job the chatter-free cuts seen (by speed and depth) and the
  // depths at which it chattered.
  struct StableCut {
    double rpm = 0, depth_mm = 0, feed_per_tooth_mm = 1e9;
    std::uint32_t revolutions = 0;
  };
  struct JobEvidence {
    std::map<std::pair<long, long>, StableCut> stable;  // (rpm, depth in µm)
    std::vector<std::pair<double, double>> chatter;     // (rpm, depth)
  };
  std::map<std::string, smc_data_ForceSummary> last_summary;  // by machine
  // The feed per tooth of each machine's last revolution cut at a feed: the
  // revolution a detector decides on is often held already (module A).
  std::map<std::string, double> last_cut_feed;
  std::map<std::string, std::string> cutting;   // machine -> job
  std::map<std::string, JobEvidence> evidence;  // by job id
  std::set<std::string> chatter_seen;           // "<machine>#<event id>"
  std::set<std::string> retired;                // machines that take no new jobs
  std::map<std::string, std::string> out_on;    // machine -> job whose assignment was sent
  int64_t data_version = -1;
  // Frozen longer than this: peers may have dropped this participant (half
  // its lease, which is how long they keep it after its last message).
  std::chrono::nanoseconds rejoin_after = participant.lease() / 2;
  FreezeWatch freeze_watch;
  Clock::time_point started = Clock::now();
  Clock::time_point last_scan{};

  explicit Impl(ServiceOptions o)
      : opt(std::move(o)),
        lock(opt.db_path),
        db(store::Store::open(opt.db_path, store::OpenMode::kExisting)),
        planner(opt.grafcet_dir, load_defaults(opt.defaults_file),
                PlannerOptions{.guard_smc1 = opt.guard_smc1}),
        participant({.domain_id = opt.domain_id, .partition = opt.partition}),
        config_writer(participant),
        job_writer(participant),
        status_doc_writer(participant),
        catalog_writer(participant),
        edge_topic(participant),
        edge_reader(edge_topic),
        progress_topic(participant),
        progress_reader(progress_topic),
        summary_topic(participant),
        summary_reader(summary_topic),
        chatter_topic(participant),
        chatter_reader(chatter_topic),
        program_reader(participant),
        dispatcher(participant) {
    dispatcher.on_instances(
        edge_reader,
        [this](const smc_data_EdgeStatus& s, const tr::SampleInfo&) { on_edge_status(s); },
        [this](const smc_data_EdgeStatus& s, tr::InstanceState) { on_edge_gone(s); });
    dispatcher.on(progress_reader, [this] { take_progress(); });
    dispatcher.on(chatter_reader, [this] { take_chatter(); });
    dispatcher.poll([this] { take_summaries(); });  // high rate: in batches, never a wake-up
    dispatcher.on(program_reader.reader(), [this] { take_programs(); });
    refresh_machines();
  }

  // The catalog in use and what the cell would choose for each part, for
  // dashboards: published at start and whenever it changed.
  void publish_catalog() {
    try {
      cfg::CatalogView view;
      *view.mutable_catalog() = store::export_catalog(db);
      const auto now = Clock::now();
      for (const auto& part : db.parts()) {
        if (part.retired_at_ms != 0) continue;
        store::Job job;
        job.id = "(part " + part.id + ")";
        job.spec.set_part_id(part.id);
        job.spec.set_tool_id(part.tool_id);
        job.spec.set_spindle_rpm(part.spindle_rpm);
        job.spec.set_feedrate_mm_s(part.feedrate_mm_s);
        job.spec.set_depth_mm(part.total_depth_mm);
        auto* choice = view.add_parts();
        choice->set_part_id(part.id);
        if (part.tool_id.empty()) {
          choice->set_variant(cfg::SMC_UNSPECIFIED);
          choice->set_explanation("no default tool: a job must name one");
          continue;
        }
        if (const auto t = db.tool(part.tool_id); t && t->retired_at_ms != 0) {
          choice->set_variant(cfg::SMC_UNSPECIFIED);
          choice->set_explanation("default tool " + part.tool_id +
                                  " is retired: a job must name another");
          continue;
        }
        Selection sel;
        const PlanInputs in = bind_job(db, job, sel, [&](const std::string& id) {
          const auto it = mills.find(id);
          return it != mills.end() && !edge_lost_past_grace(it->second.alive, it->second.lost_since,
                                                            started, now, opt.edge_grace);
        });
        choice->set_variant(sel.variant);
        choice->set_machine_id(sel.variant == cfg::SMC_I || sel.variant == cfg::SMC_II_PLUS
                                   ? in.machine.id
                                   : std::string());
        choice->set_explanation(sel.explanation);
        if (sel.force) choice->add_model_ids(sel.force->id);
        if (sel.milling) choice->add_model_ids(sel.milling->id);
      }
      for (const auto& m : db.machines()) {
        if (m.retired_at_ms != 0) continue;
        for (auto& n : channel_notes(db, m)) {
          auto* note = view.add_machine_notes();
          note->set_machine_id(m.id);
          note->set_model_id(std::move(n.model_id));
          note->set_text(std::move(n.text));
        }
      }
      const std::string body = view.SerializeAsString();
      if (body == catalog_sent) return;
      catalog_sent = body;
      view.set_updated_at_ms(std::chrono::duration_cast<std::chrono::milliseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count());
      catalog_writer.publish("cell", "catalog", view);
    } catch (const std::exception& e) {  // a dashboard's view never stops the cell
      spdlog::error("the catalog cannot be published: {}", e.what());
    }
  }

  // The machines the cell dispatches to: those of the database that are not
  // retired. Read at start and whenever the database changes, so a machine
  // added by `smc-cell catalog apply` becomes eligible without a restart.
  void refresh_machines() {
    for (const auto& m : db.machines()) {
      if (m.retired_at_ms != 0) {
        if (retired.insert(m.id).second) spdlog::info("machine {} is retired", m.id);
        continue;
      }
      if (mills.find(m.id) == mills.end()) {
        mills[m.id];
        spdlog::info("machine {} ({}) is in the cell", m.id, m.name);
      }
      retired.erase(m.id);
    }
  }

  static cfg::SupervisorConfig load_defaults(const std::string& path) {
    cfg::SupervisorConfig d;
    smc::documents::load(path, d);
    return d;
  }

  // ------------------------------------------------------------ helpers --

  void publish_status(const store::Job& j, const std::string& reason) {
    cfg::JobStatus st;
    *st.mutable_job() = j.spec;
    st.mutable_job()->set_job_id(j.id);
    st.set_state(j.state);
    st.set_variant(j.variant);
    st.set_explanation(j.explanation);
    st.set_machine_id(j.machine_id);
    st.set_attempt(j.attempt);
    if (j.plan) st.set_passes_planned(static_cast<uint32_t>(j.plan->program().passes_size()));
    const auto it = progress.find(j.id);
    if (it != progress.end()) {
      st.set_pass_index(it->second.pass_index);
      st.set_pass_count(it->second.pass_count);
      st.set_fraction_done(it->second.fraction);
      st.set_chatter_events(it->second.chatter);
    } else {
      st.set_pass_count(st.passes_planned());
    }
    if (j.state == cfg::JOB_DONE) st.set_fraction_done(1.0);
    if (j.result) *st.mutable_result() = *j.result;
    st.set_updated_unix_ms(smc::unix_time_ms());
    st.set_reason(reason);
    try {
      status_doc_writer.publish(j.id, j.id, st);
    } catch (const std::exception& e) {  // one bad record never stops the cell
      spdlog::error("job {}: its status cannot be published: {}", j.id, e.what());
    }
  }

  bool move(const store::Job& j, cfg::JobState to, const std::string& reason,
            const std::string& machine = {}) {
    const auto ev = db.transition(j.id, j.state, to, reason, machine);
    if (!ev) return false;
    spdlog::info("job {}: {} -> {} ({})", j.id, store::state_name(j.state), store::state_name(to),
                 reason);
    if (auto now = db.job(j.id)) publish_status(*now, reason);
    return true;
  }

  void withdraw(const std::string& machine) {
    cfg::JobAssignment none;
    job_writer.publish(machine, "none", none);
  }

  void send(const store::Job& j, const store::Machine& m, uint32_t attempt) {
    const auto structure = structure_model(db, j, m.id);
    const cfg::SupervisorConfig c = Planner::for_machine(*j.plan, m, config_id_for(j, attempt),
                                                         structure ? &*structure : nullptr);
    config_writer.publish(m.id, c.config_id(), c);
    cfg::JobAssignment a;
    a.set_job_id(j.id);
    a.set_config_id(c.config_id());
    a.set_attempt(attempt);
    job_writer.publish(m.id, j.id, a);
    out_on[m.id] = j.id;
  }

  // An assignment whose job left assigned/running behind the cell's back
  // (smc-cell job cancel) is withdrawn from its mill.
  void withdraw_stale_assignments() {
    for (auto it = out_on.begin(); it != out_on.end();) {
      const auto j = db.job(it->second);
      if (j && (j->state == cfg::JOB_ASSIGNED || j->state == cfg::JOB_RUNNING) &&
          j->machine_id == it->first) {
        ++it;
        continue;
      }
      spdlog::info("{}: assignment of job {} withdrawn ({})", it->first, it->second,
                   j ? std::string(store::state_name(j->state)) : "no such job");
      withdraw(it->first);
      it = out_on.erase(it);
    }
  }

  // ---------------------------------------------------------- planning --

  void plan_queued() {
    for (const auto& j : db.jobs({.state = cfg::JOB_QUEUED, .with_documents = true})) {
      try {
        // Bound to the machine whose models it uses (SMC I; machines whose
        // edge is not given up preferred), or to none (SMC II: any free mill).
        Selection sel;
        const auto now = Clock::now();
        const PlanInputs in = bind_job(db, j, sel, [&](const std::string& id) {
          const auto it = mills.find(id);
          return it != mills.end() && !edge_lost_past_grace(it->second.alive, it->second.lost_since,
                                                            started, now, opt.edge_grace);
        });
        const Plan plan = planner.plan(in, sel);
        // Verify now: the configuration the edge will get must be valid.
        auto check_on = in.machine;
        if (check_on.id.empty()) {
          const auto all = db.machines();
          if (all.empty()) throw std::runtime_error("the database has no machines");
          check_on = all.front();
        }
        const auto structure = structure_model(db, j, check_on.id);
        (void)smc::supervision::validate(Planner::for_machine(plan.config, check_on, "check",
                                                              structure ? &*structure : nullptr));
        db.set_plan(j.id, sel.variant, plan.config.explanation(), plan.config, plan.machine_id,
                    plan.model_ids);
        move(*db.job(j.id), cfg::JOB_PLANNED,
             std::string(store::variant_name(sel.variant)) +
                 (plan.machine_id.empty() ? "" : " for " + plan.machine_id) + " planned in " +
                 std::to_string(static_cast<int>(plan.planning_s * 1000)) + " ms");
      } catch (const std::exception& e) {
        spdlog::error("job {}: cannot be planned: {}", j.id, e.what());
        move(j, cfg::JOB_FAILED, std::string("cannot be planned: ") + e.what());
      }
    }
  }

  // ----------------------------------------------------------- dispatch --

  std::set<std::string> busy_machines() {
    std::set<std::string> busy;
    for (auto s : {cfg::JOB_ASSIGNED, cfg::JOB_RUNNING}) {
      for (const auto& j : db.jobs({.state = s})) busy.insert(j.machine_id);
    }
    return busy;
  }

  void dispatch() {
    const auto planned = db.jobs({.state = cfg::JOB_PLANNED, .with_documents = true});
    std::vector<PlannedJob> candidates;
    for (const auto& j : planned) {
      // A tool retired since the plan (found broken on another job) cuts
      // nothing more: the job fails with the reason.
      if (const auto t = db.tool(j.spec.tool_id()); t && t->retired_at_ms != 0) {
        move(j, cfg::JOB_FAILED,
             "tool " + t->id +
                 " was retired after the job was planned (`smc-cell catalog show "
                 "tool " +
                 t->id + "` says why); submit it again with another tool");
        continue;
      }
      // A plan made from one machine's models goes only to that machine.
      const std::string& on = j.spec.machine_id().empty() ? j.planned_for : j.spec.machine_id();
      candidates.push_back({j.id, j.spec.priority(), on, j.attempt});
    }
    std::vector<MillView> views;
    for (const auto& [id, mill] : mills) {
      if (retired.count(id)) continue;
      views.push_back({id, mill.alive,
                       mill.state == smc_data_EDGE_IDLE || mill.state == smc_data_EDGE_CONFIGURED});
    }
    for (const Assignment& a : choose_assignments(candidates, views, busy_machines())) {
      const auto j = db.job(a.job_id);
      const auto m = db.machine(a.machine_id);
      if (!j || !m) continue;
      // The structure send() gives module E, said in the job's history.
      const auto structure = structure_model(db, *j, a.machine_id);
      const std::string note =
          j->plan ? Planner::structure_note(*j->plan, structure ? &*structure : nullptr) : "";
      if (!move(*j, cfg::JOB_ASSIGNED,
                "dispatched to " + a.machine_id + " (attempt " + std::to_string(a.attempt) + ")" +
                    (note.empty() ? "" : "; " + note),
                a.machine_id))
        continue;
      try {
        send(*db.job(a.job_id), *m, a.attempt);
      } catch (const std::exception& e) {
        fail_unsendable(a.job_id, e.what());
      }
    }
  }

  // On start-up: jobs the database says are out on mills get their
  // configuration and assignment again (an edge ignores what it already ran).
  // A job whose configuration or assignment cannot be sent (a record the
  // wire cannot carry) fails with the reason; the cell goes on.
  void fail_unsendable(const std::string& job_id, const std::string& why) {
    spdlog::error("job {}: cannot be sent to its mill: {}", job_id, why);
    try {
      auto j = db.job(job_id);
      if (!j) return;
      if (j->state == cfg::JOB_ASSIGNED || j->state == cfg::JOB_RUNNING) {
        withdraw(j->machine_id);
        if (move(*j, cfg::JOB_INTERRUPTED, "cannot be sent: " + why)) j = db.job(job_id);
      }
      if (j && !store::is_terminal(j->state)) {
        move(*j, cfg::JOB_FAILED, "cannot be sent: " + why);
      }
    } catch (const std::exception& e) {
      spdlog::error("job {}: cannot be marked failed either: {}", job_id, e.what());
    }
  }

  void resume() {
    for (auto s : {cfg::JOB_ASSIGNED, cfg::JOB_RUNNING}) {
      for (const auto& j : db.jobs({.state = s, .with_documents = true})) {
        const auto m = db.machine(j.machine_id);
        if (!m || !j.plan) continue;
        spdlog::info("job {}: resuming as {} on {}", j.id, store::state_name(j.state),
                     j.machine_id);
        try {
          send(j, *m, j.attempt);
        } catch (const std::exception& e) {
          fail_unsendable(j.id, e.what());
        }
      }
    }
  }

  // ------------------------------------------------------------- edges --

  void on_edge_status(const smc_data_EdgeStatus& s) {
    const std::string id = get_string(s.machine_id);
    auto it = mills.find(id);
    if (it == mills.end()) return;
    if (!it->second.alive) spdlog::info("edge {} is alive", id);
    it->second.alive = true;
    it->second.seen = true;
    it->second.state = s.state;
  }

  void on_edge_gone(const smc_data_EdgeStatus& key) {
    auto it = mills.find(get_string(key.machine_id));
    if (it == mills.end() || !it->second.alive) return;
    spdlog::warn("edge {} lost (liveliness)", it->first);
    it->second.alive = false;
    it->second.lost_since = Clock::now();
  }

  void check_lost_edges() {
    const auto now = Clock::now();
    for (auto s : {cfg::JOB_ASSIGNED, cfg::JOB_RUNNING}) {
      for (const auto& j : db.jobs({.state = s})) {
        const Mill& m = mills[j.machine_id];
        if (!edge_lost_past_grace(m.alive, m.lost_since, started, now, opt.edge_grace)) continue;
        interrupt(j, "edge " + j.machine_id +
                         (m.seen ? " lost (liveliness)" : " not seen since the cell started"));
      }
    }
  }

  void interrupt(const store::Job& j, const std::string& why) {
    if (!move(j, cfg::JOB_INTERRUPTED, why)) return;
    withdraw(j.machine_id);
    const auto now = *db.job(j.id);
    const AfterInterruption next = after_interruption(now.attempt, opt.max_attempts);
    move(now, next.requeue ? cfg::JOB_QUEUED : cfg::JOB_FAILED, next.reason);
  }

  // ---------------------------------------------------------- progress --

  void take_progress() {
    progress_reader.take([&](const smc_data_JobProgress& p, const tr::SampleInfo& info) {
      if (!info.valid_data) return;
      const std::string job_id = get_string(p.job_id);
      auto j = db.job(job_id);
      if (!j || j->machine_id != get_string(p.machine_id)) return;
      Progress& pr = progress[job_id];
      pr.pass_index = p.pass_index;
      pr.pass_count = p.pass_count;
      pr.fraction = p.fraction_done;
      pr.chatter = std::max(pr.chatter, p.chatter_events);
      pr.peak_force = p.peak_force_n;
      const std::string msg = get_string(p.message);
      if (p.phase == smc_data_JOB_RUNNING) {
        cutting[j->machine_id] = job_id;
        recording[j->machine_id] = job_id;
      }
      if (p.phase == smc_data_JOB_DONE || p.phase == smc_data_JOB_FAILED ||
          p.phase == smc_data_JOB_INTERRUPTED) {
        record_stable_cuts(*j);
        flush_history();
      }
      switch (p.phase) {
        case smc_data_JOB_RUNNING:
          if (j->state == cfg::JOB_ASSIGNED)
            move(*j, cfg::JOB_RUNNING, "edge " + j->machine_id + ": " + msg);
          else if (j->state == cfg::JOB_RUNNING)
            publish_status(*j, msg);
          break;
        case smc_data_JOB_DONE:
          if (j->state == cfg::JOB_ASSIGNED) move(*j, cfg::JOB_RUNNING, "edge reported progress");
          if (auto cur = db.job(job_id); cur && cur->state == cfg::JOB_RUNNING) {
            cfg::RunSummary r;
            r.set_config_id(config_id_for(*cur, cur->attempt));
            r.set_variant(cur->variant);
            r.set_completed(true);
            r.set_passes_completed(p.pass_count);
            if (cur->plan)
              r.set_passes_planned(static_cast<uint32_t>(cur->plan->program().passes_size()));
            // Counted by the edge from its events: the programs it publishes
            // are not all seen here (keep-last 1).
            r.set_program_rewrites(p.program_rewrites);
            r.set_spindle_speed_changes(p.spindle_speed_changes);
            r.set_depth_removed_mm(p.depth_removed_mm);
            r.set_chatter_events(pr.chatter);
            r.set_peak_force_n(p.peak_force_n);
            r.set_cycle_time_s(static_cast<double>(p.machine_time_ns) * 1e-9);
            if (cur->plan && cur->plan->program().passes_size() > 0) {
              // F_ref as the edge computes it (services/supervision).
              const auto& pl = *cur->plan;
              const auto m = db.machine(cur->machine_id);
              double ref =
                  pl.operation().force_reference_n() > 0
                      ? pl.operation().force_reference_n()
                      : smc::supervision::force_reference_n(m ? m->max_spindle_power_w : 0,
                                                            pl.operation().cutter_radius_mm(),
                                                            pl.program().passes(0).spindle_rpm(),
                                                            pl.operation().force_safety_factor());
              // The reference the edge held: each pass's planned F_ref (SMC I)
              // as module M scaled it, the highest over the revolutions cut
              // (recorded in the job's history); the estimate above when none
              // was recorded.
              double held = 0;
              for (const auto& rev : db.revolutions(job_id)) {
                if (rev.attempt == cur->attempt && rev.in_contact)
                  held = std::max(held, rev.f_ref_n);
              }
              if (held > 0) ref = held;
              r.set_force_reference_n(ref);
              if (ref > 0)
                r.set_overshoot_pct(100.0 * (static_cast<double>(p.peak_force_n) - ref) / ref);
            }
            db.record_result(job_id, r);
            move(*db.job(job_id), cfg::JOB_DONE, "edge " + cur->machine_id + ": " + msg);
            withdraw(cur->machine_id);
            learn(*db.job(job_id));
          }
          break;
        case smc_data_JOB_FAILED:
          if (j->state == cfg::JOB_RUNNING || j->state == cfg::JOB_ASSIGNED) {
            if (j->state == cfg::JOB_ASSIGNED) move(*j, cfg::JOB_RUNNING, "edge reported progress");
            move(*db.job(job_id), cfg::JOB_FAILED, "edge " + j->machine_id + ": " + msg);
            withdraw(j->machine_id);
            if (msg.rfind(kToolBreakage, 0) == 0) mark_tool_broken(*db.job(job_id), msg);
          }
          break;
        case smc_data_JOB_INTERRUPTED:
          if (j->state == cfg::JOB_RUNNING || j->state == cfg::JOB_ASSIGNED)
            interrupt(*j, "edge " + j->machine_id + ": " + msg);
          break;
        case smc_data_JOB_ASSIGNED:
          break;
      }
    });
  }

  // Module N stopped a job: the tool it used is retired (recorded in the
  // catalog's history with the reason), so that no new job is planned with
  // it until a new tool is entered.
  static constexpr const char* kToolBreakage = "tool breakage";
  void mark_tool_broken(const store::Job& j, const std::string& msg) {
    const std::string tool = j.spec.tool_id();
    if (tool.empty()) return;
    try {
      db.retire("tool", tool, "cell", "broken in job " + j.id + " on " + j.machine_id + ": " + msg);
      spdlog::error("tool {} retired: broken in job {} on {}", tool, j.id, j.machine_id);
    } catch (const std::exception& e) {
      spdlog::warn("tool {} not retired: {}", tool, e.what());  // retired already, or gone
    }
  }

  void take_chatter() {
    chatter_reader.take([&](const smc_data_ChatterEvent& e, const tr::SampleInfo& info) {
      if (!info.valid_data) return;
      const std::string machine = get_string(e.machine_id);
      if (!chatter_seen.insert(machine + "#" + std::to_string(e.event_id)).second) return;
      const bool automatic = e.source == smc_data_CHATTER_AUTOMATIC;
      if (e.new_spindle_rpm > 0) {
        spdlog::warn("{}: chatter ({}) at {:.0f} Hz in job {}, spindle speed now {:.0f} rpm",
                     machine, automatic ? "automatic" : "operator", e.frequency_hz,
                     get_string(e.job_id), e.new_spindle_rpm);
      } else {
        spdlog::warn("{}: chatter ({}) at {:.0f} Hz in job {}, program now {} passes", machine,
                     automatic ? "automatic" : "operator", e.frequency_hz, get_string(e.job_id),
                     e.new_pass_count);
      }
      try {
        record_chatter(e, machine, automatic);
      } catch (const std::exception& ex) {
        spdlog::error("{}: chatter event {} not recorded: {}", machine, e.event_id, ex.what());
      }
    });
  }

  // A chatter event goes into its job's history. Under SMC I the plan was
  // made chatter-free from the machine's models, so automatic chatter is
  // evidence against them: the models the plan used are marked suspect, and
  // later jobs for the part are planned without them (SMC II) until someone
  // validates them again.
  void record_chatter(const smc_data_ChatterEvent& e, const std::string& machine, bool automatic) {
    const auto j = db.job(get_string(e.job_id));
    if (!j) return;
    const std::string tag = "chatter event " + std::to_string(e.event_id) + " on " + machine;
    for (const auto& ev : db.events(j->id)) {
      if (ev.reason.rfind(tag + ":", 0) == 0) return;  // recorded before a restart
    }
    char what[160];
    std::snprintf(what, sizeof what, "%s at %.0f Hz in pass %u (detector statistic %.2f)",
                  automatic ? "detected" : "signalled by the operator",
                  static_cast<double>(e.frequency_hz), e.pass_index + 1u,
                  static_cast<double>(e.energy_ratio));
    std::string reason =
        tag + ": " + what + "; program now " + std::to_string(e.new_pass_count) + " passes";
    if (e.new_spindle_rpm > 0) {
      // SMC II+: module O moved the spindle instead of adding a pass.
      reason += ", spindle speed changed to " +
                std::to_string(static_cast<int>(std::lround(e.new_spindle_rpm))) + " rpm";
    }
    if (automatic && j->variant == cfg::SMC_I) {
      const auto models = db.plan_models(j->id);
      bool from_cuts = true;  // no milling model: planned from the part's own cuts
      for (const auto& id : models) {
        const auto m = db.model(id);
        from_cuts = from_cuts && !(m && m->kind == store::ModelKind::kMilling);
      }
      if (from_cuts) {
        // The chatter point recorded below lies at or under the depth the
        // part was cut clean at: the bound disagrees with itself and no
        // longer stands in for a structural model. The force model did not
        // plan the depth and stays.
        reason +=
            "; the plan kept to depths the part had cut without chatter at this speed; "
            "this chatter contradicts that evidence, so part " +
            j->spec.part_id() + " is demoted: its later jobs on " + machine +
            " are SMC II until a structural model is validated";
        db.record_catalog_event("part", j->spec.part_id(), "demoted", "cell",
                                "job " + j->id +
                                    ": the SMC I plan from the part's cuts chattered on " +
                                    machine + " (" + what + ")");
      } else {
        const std::string why = "the SMC I plan of job " + j->id + " made from it chattered on " +
                                machine + " (" + what + ")";
        for (const auto& id : models) db.mark_model_suspect(id, why);
        std::string ids;
        for (const auto& id : models) ids += (ids.empty() ? "" : ", ") + id;
        reason += "; the plan was made chatter-free from models " + (ids.empty() ? "(none)" : ids) +
                  ", so they are marked suspect and part " + j->spec.part_id() +
                  " is demoted: its later jobs are planned without them";
        db.record_catalog_event(
            "part", j->spec.part_id(), "demoted", "cell",
            "job " + j->id + ": " + why + "; its models " + ids + " are marked suspect");
        spdlog::warn("job {}: models {} marked suspect", j->id, ids);
      }
    }
    db.note_event(j->id, reason);
    record_chatter_point(*j, machine, automatic ? double{e.frequency_hz} : 0.0);
  }

  // ------------------------------------------------ stability evidence --

  store::StabilityEvidence evidence_for(const store::Job& j) {
    store::StabilityEvidence e;
    e.part_id = j.spec.part_id();
    e.machine_id = j.machine_id;
    e.tool_id = j.spec.tool_id();
    e.job_id = j.id;
    if (const auto part = db.part(j.spec.part_id())) e.width_mm = part->width_mm;
    return e;
  }

  // Chatter at the speed, depth and feed of the machine's last revolution
  // (the one the detector decided on).
  void record_chatter_point(const store::Job& j, const std::string& machine, double hz) {
    const auto it = last_summary.find(machine);
    if (it == last_summary.end() || !(it->second.depth_mm > 0)) return;
    store::StabilityEvidence e = evidence_for(j);
    e.spindle_rpm = it->second.spindle_rpm;
    e.depth_mm = it->second.depth_mm;
    const auto feed = last_cut_feed.find(machine);
    e.feed_per_tooth_mm =
        feed != last_cut_feed.end() ? feed->second : double{it->second.feed_per_tooth_mm};
    e.chatter = true;
    e.frequency_hz = hz;
    db.add_stability_evidence(e);
    evidence[j.id].chatter.emplace_back(e.spindle_rpm, e.depth_mm);
  }

  // At the end of a job: each depth it cut without chatter for at least 20
  // revolutions, unless it chattered at that speed at that depth or
  // shallower (the detector decides a few revolutions after onset, so the
  // revolutions just before a detection were not stable).
  void record_stable_cuts(const store::Job& j) {
    const auto it = evidence.find(j.id);
    if (it == evidence.end()) return;
    for (const auto& [key, c] : it->second.stable) {
      bool contradicted = false;
      for (const auto& [rpm, depth] : it->second.chatter) {
        contradicted = contradicted || (std::fabs(rpm - c.rpm) < 1 && depth <= c.depth_mm + 1e-6);
      }
      if (c.revolutions < 20 || contradicted) continue;
      store::StabilityEvidence e = evidence_for(j);
      e.spindle_rpm = c.rpm;
      e.depth_mm = c.depth_mm;
      e.feed_per_tooth_mm = c.feed_per_tooth_mm < 1e9 ? c.feed_per_tooth_mm : 0;
      e.revolutions = c.revolutions;
      db.add_stability_evidence(e);
    }
    evidence.erase(it);
    for (auto m = cutting.begin(); m != cutting.end();) {
      m = m->second == j.id ? cutting.erase(m) : std::next(m);
    }
  }

  // ---------------------------------------------------------- learning --

  // ------------------------------------------------------- job history --

  // The programs a job ran: each one its mill publishes while the job runs
  // (rewrites, speed changes; the plan's is the job's plan).
  void take_programs() {
    program_reader.take(
        [&](const std::string& machine, const cfg::PartProgram& p) {
          const auto it = recording.find(machine);
          if (it == recording.end()) return;
          const auto j = db.job(it->second);
          if (!j) return;
          store::JobProgram jp;
          jp.attempt = j->attempt;
          jp.revision = p.revision();
          jp.gcode = p.gcode();
          jp.passes = static_cast<std::uint32_t>(p.passes_size());
          try {
            db.add_program(j->id, jp);
          } catch (const std::exception& e) {
            spdlog::warn("job {}: program revision {} not recorded: {}", j->id, p.revision(),
                         e.what());
          }
        },
        [](const tr::EnvelopeRejection&) {});
  }

  void flush_history() {
    history_flushed = Clock::now();
    for (auto& [job_id, revs] : history) {
      if (revs.empty()) continue;
      try {
        const auto j = db.job(job_id);
        if (!j) continue;
        for (auto& r : revs) r.attempt = j->attempt;
        db.append_revolutions(job_id, revs);
      } catch (const std::exception& e) {
        spdlog::warn("job {}: {} revolutions of its history not recorded: {}", job_id, revs.size(),
                     e.what());
      }
      revs.clear();
    }
    std::erase_if(history, [](const auto& kv) { return kv.second.empty(); });
  }

  void take_summaries() {
    summary_reader.take([&](const smc_data_ForceSummary& s, const tr::SampleInfo& info) {
      if (!info.valid_data) return;
      const std::string machine = get_string(s.machine_id);
      last_summary[machine] = s;
      if (s.in_contact && s.feed_per_tooth_mm > 0) last_cut_feed[machine] = s.feed_per_tooth_mm;
      if (auto it = recording.find(machine); it != recording.end()) {
        store::JobRevolution r;
        r.t_s = static_cast<double>(s.machine_time_ns) * 1e-9;
        r.revolution = s.revolution;
        r.pass_index = s.pass_index;
        r.pass_count = s.pass_count;
        r.depth_mm = s.depth_mm;
        r.f_y_n = s.f_y_peak_n;
        r.f_ref_n = s.f_ref_n;
        r.feedrate_mm_s = s.feedrate_mm_s;
        r.feed_per_tooth_mm = s.feed_per_tooth_mm;
        r.spindle_rpm = s.spindle_rpm;
        r.spindle_power_w = s.spindle_power_w;
        r.in_contact = s.in_contact;
        r.chatter = s.chatter;
        history[it->second].push_back(r);
      }
      if (s.in_contact && !s.chatter && s.depth_mm > 0 && s.spindle_rpm > 0) {
        if (auto it = cutting.find(machine); it != cutting.end()) {
          auto& c =
              evidence[it->second]
                  .stable[{std::lround(s.spindle_rpm), std::lround(1000.0 * double{s.depth_mm})}];
          c.rpm = s.spindle_rpm;
          c.depth_mm = s.depth_mm;
          // The lowest feed it was cut at (held revolutions cut nothing).
          if (s.feed_per_tooth_mm > 0)
            c.feed_per_tooth_mm = std::min(c.feed_per_tooth_mm, double{s.feed_per_tooth_mm});
          ++c.revolutions;
        }
      }
      if (!opt.learn || !s.in_contact || s.chatter) return;
      if (!(s.f_y_peak_n > 0) || !(s.feed_per_tooth_mm > 0) || !(s.depth_mm > 0)) return;
      // Settled revolutions only: the cutter fully in the part and the
      // controller at its reference (entry, exit and transients mix the
      // engagement into the force, which the model does not describe).
      if (!(s.f_ref_n > 0) || std::fabs(s.f_y_peak_n - s.f_ref_n) > 0.1f * s.f_ref_n) return;
      for (const auto& j : db.jobs({.state = cfg::JOB_RUNNING})) {
        if (j.machine_id != get_string(s.machine_id) ||
            (j.variant != cfg::SMC_II && j.variant != cfg::SMC_II_PLUS))
          continue;
        // Eq. 1 has no speed term: only revolutions at the job's programmed
        // speed (SMC II+ may move the spindle).
        const double rpm = j.spec.spindle_rpm();
        if (rpm > 0 && std::fabs(double{s.spindle_rpm} - rpm) > 0.01 * rpm) continue;
        learning[j.id].push_back({s.depth_mm, s.feed_per_tooth_mm, s.f_y_peak_n});
      }
    });
    if (!history.empty() && Clock::now() - history_flushed > std::chrono::milliseconds(500)) {
      flush_history();
    }
  }

  // What a finished job teaches the cell about its part (cell/README.md,
  // "Learning and promotion"):
  //  - every candidate force model of the part on that machine is checked on
  //    the run's settled revolutions; one that predicts F_Y within the
  //    policy's tolerance for its number of runs in a row is validated;
  //  - when none predicted this run, a new candidate is fitted from it;
  //  - every unvalidated milling model of the part on that machine is
  //    checked against the stability limit its cuts bound at this speed:
  //    validated when its limit lies between a clean cut and a chatter,
  //    marked suspect when either contradicts it;
  //  - when a job of the part would now get SMC I and this one did not, the
  //    part is promoted: a note in the job's history and the part's.
  void learn(const store::Job& j) {
    std::vector<machining::ForceSample> samples;
    if (auto it = learning.find(j.id); it != learning.end()) {
      samples = std::move(it->second);
      learning.erase(it);
    }
    const auto part = db.part(j.spec.part_id());
    if (!part || j.machine_id.empty()) return;
    const bool was_smc1 = j.variant == cfg::SMC_I;
    bool predicted = false;
    if (samples.size() >= policy.min_samples) {
      for (const auto& m :
           db.find_models(j.machine_id, j.spec.tool_id(), part->material_id, part->id)) {
        if (m.kind != store::ModelKind::kForceProcess || m.part_id != part->id || m.validated ||
            m.provenance != cfg::PROVENANCE_FITTED || !m.suspect_reason.empty())
          continue;
        predicted = check_force_model(j, m, samples) || predicted;
      }
      if (!predicted && opt.learn) fit_candidate(j, *part, samples);
    }
    check_milling_models(j, *part);
    if (!was_smc1) note_promotion(j);
  }

  // One check of a candidate force model on a run; true when it passed.
  bool check_force_model(const store::Job& j, const store::ProcessModel& m,
                         const std::vector<machining::ForceSample>& samples) {
    const double err = mean_abs_error_pct(machining::from_proto(m.force, "force_model"), samples);
    const bool passed = std::isfinite(err) && err <= policy.within_pct;
    char reason[200];
    std::snprintf(reason, sizeof reason,
                  "job %s: predicted F_Y of its %zu settled revolutions within %.1f %% (mean "
                  "absolute error; the policy asks %.0f %%)",
                  j.id.c_str(), samples.size(), err, policy.within_pct);
    db.record_catalog_event("model", m.id, "checked", "cell", reason, passed ? "passed" : "failed");
    spdlog::info("model {}: {} ({})", m.id, reason, passed ? "passed" : "failed");
    if (!passed) return false;
    const int in_a_row = passed_in_a_row(db.history("model", m.id));
    if (in_a_row < policy.runs) return true;
    std::string jobs;
    for (const auto& e : db.history("model", m.id)) {
      if (e.action == "checked" && e.detail == "passed")
        jobs += (jobs.empty() ? "" : ", ") + e.reason.substr(4, e.reason.find(':') - 4);
    }
    const std::string why = "predicted F_Y of " + std::to_string(in_a_row) +
                            " runs in a row within " + std::to_string(int(policy.within_pct)) +
                            " % (jobs " + jobs + ")";
    judge(j, "force model", m.id, true, why);
    return true;
  }

  // What the cell's learning concluded about a model, in one transaction:
  // validated or suspect, in the model's history and in the job's notes.
  void judge(const store::Job& j, const char* what, const std::string& id, bool valid,
             const std::string& why) {
    db.transaction([&] {
      if (valid) {
        db.set_model_validated(id, true);
      } else {
        db.mark_model_suspect(id, why);
      }
      db.record_catalog_event("model", id, valid ? "validated" : "suspected", "cell", why);
      db.note_event(j.id, std::string(what) + " " + id +
                              (valid ? " validated: " : " marked suspect: ") + why);
    });
    if (valid) {
      spdlog::info("model {} validated: {}", id, why);
    } else {
      spdlog::warn("model {} marked suspect: {}", id, why);
    }
  }

  // A candidate force-process model (F_Y = K d^beta f^alpha) fitted from a
  // run's settled revolutions, stored as not validated. Under force control
  // F_Y sits at the reference: the settled revolutions lie along one force
  // level (or one per pass), which fixes K for given exponents but not the
  // exponents themselves. An exponent is held at the handbook value of the
  // paper's eq. 1 when the data cannot fix it: one depth (or one feed), forces
  // that span less than 1.5:1, or a 95 % interval wider than +/- 0.15 when
  // fitted; the note says which, with K's 95 % interval.
  void fit_candidate(const store::Job& j, const store::Part& part,
                     const std::vector<machining::ForceSample>& samples) {
    double dmin = 1e9, dmax = 0, fmin = 1e9, fmax = 0, force_min = 1e9, force_max = 0;
    for (const auto& s : samples) {
      dmin = std::min(dmin, s.depth_mm);
      dmax = std::max(dmax, s.depth_mm);
      fmin = std::min(fmin, s.feed_mm_per_tooth);
      fmax = std::max(fmax, s.feed_mm_per_tooth);
      force_min = std::min(force_min, s.force_n);
      force_max = std::max(force_max, s.force_n);
    }
    machining::FitOptions fo;
    std::string note =
        "fitted from " + std::to_string(samples.size()) + " revolutions of job " + j.id;
    const bool one_level = force_max < 1.5 * force_min;
    if (dmax < 1.2 * dmin || one_level) {
      fo.fixed_beta = 0.65;
      note += dmax < 1.2 * dmin ? "; beta held at 0.65 (one depth)"
                                : "; beta held at 0.65 (F_Y held at one level by the controller)";
    }
    if (fmax < 1.5 * fmin || one_level) {
      fo.fixed_alpha = 0.63;
      note += fmax < 1.5 * fmin ? "; alpha held at 0.63 (feed range too narrow to identify it)"
                                : "; alpha held at 0.63 (F_Y held at one level by the controller)";
    }
    if (!fo.fixed_beta || !fo.fixed_alpha) {
      try {
        const auto free = machining::fit_force_process(samples, fo);
        if (free.fit && !fo.fixed_beta && 1.96 * free.fit->beta_stderr > 0.15) {
          fo.fixed_beta = 0.65;
          note += "; beta held at 0.65 (fitted, its 95 % interval was wider than +/- 0.15)";
        }
        if (free.fit && !fo.fixed_alpha && 1.96 * free.fit->alpha_stderr > 0.15) {
          fo.fixed_alpha = 0.63;
          note += "; alpha held at 0.63 (fitted, its 95 % interval was wider than +/- 0.15)";
        }
      } catch (const std::exception&) {
        // refitted below with what it holds; that fit reports the error
      }
    }
    try {
      const auto fit = machining::fit_force_process(samples, fo);
      if (fit.fit) {
        char ci[160];
        std::snprintf(ci, sizeof ci, "; K %.3f +/- %.3f kN (95 %%)", fit.k_kn,
                      1.96 * fit.fit->k_stderr);
        note += ci;
        if (!fo.fixed_beta) {
          std::snprintf(ci, sizeof ci, ", beta %.2f +/- %.2f", fit.beta,
                        1.96 * fit.fit->beta_stderr);
          note += ci;
        }
        if (!fo.fixed_alpha) {
          std::snprintf(ci, sizeof ci, ", alpha %.2f +/- %.2f", fit.alpha,
                        1.96 * fit.fit->alpha_stderr);
          note += ci;
        }
      }
      store::ProcessModel pm;
      pm.kind = store::ModelKind::kForceProcess;
      pm.machine_id = j.machine_id;
      pm.tool_id = j.spec.tool_id();
      pm.material_id = part.material_id;
      pm.part_id = part.id;
      pm.provenance = cfg::PROVENANCE_FITTED;
      pm.validated = false;
      pm.force = machining::to_proto(fit);
      pm.fit = pm.force.fit();
      pm.note = note;
      const std::string id = db.add_model(pm);
      db.note_event(j.id, "candidate force model " + id + " (" + note +
                              "); validated once it predicts later runs");
      spdlog::info(
          "job {}: candidate force model {}: K={:.3f} kN beta={:.2f} alpha={:.2f}, R^2={:.3f} ({})",
          j.id, id, fit.k_kn, fit.beta, fit.alpha, fit.fit ? fit.fit->r_squared : 0.0, note);
    } catch (const std::exception& e) {
      spdlog::warn("job {}: no force model fitted: {}", j.id, e.what());
    }
  }

  // Unvalidated milling models of the part on the job's machine, against
  // the stability limit the part's cuts bound at the job's speed.
  void check_milling_models(const store::Job& j, const store::Part& part) {
    const auto tool = db.tool(j.spec.tool_id());
    if (!tool) return;
    const long rpm = std::lround(j.spec.spindle_rpm());
    std::optional<StabilityBound> bound;
    for (auto& b : stability_bounds(db.stability_evidence(part.id))) {
      if (b.machine_id == j.machine_id && b.tool_id == tool->id && b.rpm == rpm) bound = b;
    }
    if (!bound || bound->disagrees()) return;
    for (const auto& m : db.find_models(j.machine_id, tool->id, part.material_id, part.id)) {
      if (m.kind != store::ModelKind::kMilling || m.part_id != part.id || m.validated ||
          !m.suspect_reason.empty())
        continue;
      BoundCheck c;
      try {
        c = check_against(for_part(m, *tool, part), *bound);
      } catch (const std::exception& e) {
        spdlog::warn("model {}: not checked against the part's cuts: {}", m.id, e.what());
        continue;
      }
      char what[240];
      std::snprintf(what, sizeof what,
                    "its critical depth at %ld rpm is %.2f mm at the clean cut's feed and %.2f mm "
                    "at the chatter's; the part's cuts on %s bound the limit to (%.2f, %.2f] mm",
                    rpm, c.critical_at_stable_mm, c.critical_at_chatter_mm, j.machine_id.c_str(),
                    bound->stable_mm, bound->chatter_mm);
      if (c.contradicted()) {
        judge(j, "milling model", m.id, false,
              std::string("contradicted by the part's cuts: ") + what);
      } else if (c.brackets()) {
        judge(j, "milling model", m.id, true,
              std::string("consistent with the part's cuts: ") + what);
      }
    }
  }

  // The part is promoted when a job of it would now get SMC I on some
  // machine and this one did not get it.
  void note_promotion(const store::Job& j) {
    store::Job next = j;
    next.id = "next";
    next.spec.clear_machine_id();
    Selection sel;
    try {
      (void)bind_job(db, next, sel);
    } catch (const std::exception&) {
      return;
    }
    if (sel.variant != cfg::SMC_I) return;
    if (!sel.force) return;
    std::string why = "after job " + j.id + ", a job of part " + j.spec.part_id() +
                      " gets SMC I on " + sel.force->machine_id + ": force model " + sel.force->id +
                      " is validated, ";
    if (sel.milling) {
      why += "and so is milling model " + sel.milling->id;
    } else if (sel.bound) {
      char b[160];
      std::snprintf(b, sizeof b,
                    "and the part's cuts at %ld rpm bound its stability (clean to %.2f mm over %u "
                    "revolutions)",
                    sel.bound->rpm, sel.bound->stable_mm, sel.bound->revolutions);
      why += b;
    }
    db.transaction([&] {
      db.record_catalog_event("part", j.spec.part_id(), "promoted", "cell", why);
      db.note_event(j.id, "part " + j.spec.part_id() + " promoted to SMC I: " + why);
    });
    spdlog::info("part {} promoted to SMC I: {}", j.spec.part_id(), why);
  }

  // -------------------------------------------------------------- loop --

  int run(const std::atomic<bool>& stop) {
    spdlog::info("cell: database {} (schema {}), {} machines", opt.db_path, db.schema_version(),
                 mills.size());
    resume();
    for (const auto& j : db.jobs({.with_documents = true})) publish_status(j, "current");
    publish_catalog();
    while (!stop.load()) {
      if (const auto frozen = freeze_watch.take_longest(); frozen > rejoin_after) {
        spdlog::warn(
            "cell: the process was frozen for {} ms, more than half its DDS lease ({} ms): its "
            "peers may have dropped it; rejoining with a new participant",
            std::chrono::duration_cast<std::chrono::milliseconds>(frozen).count(),
            std::chrono::duration_cast<std::chrono::milliseconds>(2 * rejoin_after).count());
        flush_history();
        return CellService::kRejoinDds;
      }
      dispatcher.run_once(50ms);
      const int64_t v = db.data_version();
      if (v != data_version || Clock::now() - last_scan > 1s) {
        data_version = v;
        last_scan = Clock::now();
        refresh_machines();
        publish_catalog();
        for (const auto& j : db.jobs({.state = cfg::JOB_QUEUED})) {
          if (!progress.count(j.id)) publish_status(j, "queued");
        }
        plan_queued();
        withdraw_stale_assignments();
      }
      check_lost_edges();
      dispatch();
    }
    return 0;
  }
};

CellService::CellService(ServiceOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}
CellService::~CellService() = default;
int CellService::run(const std::atomic<bool>& stop) { return impl_->run(stop); }

}  // namespace smc::cell
