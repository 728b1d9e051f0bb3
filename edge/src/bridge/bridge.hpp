#pragma once
// The edge on DDS, split by concern: one Impl, its members here, its work in
// one file per concern (the comms thread runs all of it; the loop thread
// only the core):
//
//   service.cpp        wiring: participant, topics, the dispatcher; the loop
//   journal.cpp        the (job, attempt)s started, kept across restarts
//   status.cpp         smc_edge_status (liveliness lease)
//   config_intake.cpp  smc_config: checked in full before it is accepted
//   jobs.cpp           smc_job: start, progress, finish, interruption
//   operator.cpp       smc_operator_command → the loop's operator inputs
//   telemetry.cpp      the core's rings → summaries, batches, situations,
//                      chatter events, rewritten programs

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "smc/common/clock.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/linuxcnc_drive.hpp"
#include "smc/edge/realtime.hpp"
#include "smc/edge/service.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/transport/dispatcher.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/documents.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace tr = smc::transport;

inline uint64_t machine_ns(double t_s) { return static_cast<uint64_t>(t_s * 1e9); }

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
  std::unique_ptr<Drive> mill;   // the simulated mill or LinuxCNC
  LinuxCncDrive* cnc = nullptr;  // mill, when it is LinuxCNC
  std::string failure;           // why the job ended failed, when the edge knows
  std::unique_ptr<EdgeCore> core;
  std::unique_ptr<RealTimeEdge> rt;
  // What the comms thread knows of the loop, only from the core's rings (the
  // core itself belongs to the loop thread).
  RevolutionRecord latest{};
  FixedProgram program;
  bool done = false;
  uint32_t sequence = 0;
  uint32_t chatter_events = 0;
  uint16_t program_rewrites = 0;
  uint16_t spindle_speed_changes = 0;
  double peak_force_n = 0;
  std::chrono::steady_clock::time_point last_progress{};
};

// The intake thread: checks one configuration at a time, the newest first
// (a configuration superseded while waiting is never checked), and hands
// each verdict back. Not real-time; never touches DDS.
class ConfigIntake {
 public:
  struct Verdict {
    smc::config::SupervisorConfig config;  // as the cell sent it
    std::string why;                       // empty: accepted
  };
  using Check = std::function<std::string(const smc::config::SupervisorConfig&)>;
  // `checked` runs on the intake thread after each verdict (to wake the comms thread).
  ConfigIntake(Check check, std::function<void()> checked);
  ~ConfigIntake();
  ConfigIntake(const ConfigIntake&) = delete;
  ConfigIntake& operator=(const ConfigIntake&) = delete;

  void submit(smc::config::SupervisorConfig cfg);  // replaces one still waiting
  std::deque<Verdict> take_verdicts();
  bool idle() const;  // nothing waiting or being checked

 private:
  void run();
  Check check_;
  std::function<void()> checked_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::optional<smc::config::SupervisorConfig> waiting_;
  std::deque<Verdict> verdicts_;
  bool busy_ = false;
  bool stop_ = false;
  std::thread thread_;
};

struct EdgeService::Impl {
  explicit Impl(ServiceOptions o);
  int run(const std::atomic<bool>& stop);

  ServiceOptions opt;
  RealClock clock;
  tr::Participant participant;
  // Inputs.
  smc::wire::DocumentSubscriber<smc::config::SupervisorConfig> config_reader;
  smc::wire::DocumentSubscriber<smc::config::JobAssignment> job_reader;
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
  smc::wire::DocumentPublisher<smc::config::PartProgram> program_writer;
  tr::Dispatcher dispatcher;

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
  uint64_t chatter_id_base =
      static_cast<uint64_t>(smc::unix_time_ns() / 1000);  // survives restarts
  uint64_t chatter_seq = 0;
  uint32_t situation_seq = 0;
  std::optional<smc_data_ChatterEvent> pending_chatter;
  std::chrono::steady_clock::time_point pending_since{};
  std::chrono::steady_clock::time_point last_status{};
  std::string refused_config_id;  // the last configuration refused ...
  std::string refusal;            // ... and why, whole, on one line

  // service.cpp: the job's life and the loop's rings, on every wake-up.
  void supervise_job();

  // ---- journal.cpp
  void load_journal();
  // Durable before the job starts: a crash right after must not lose it.
  void journal(const std::string& tag);
  // ---- status.cpp
  void publish_status();
  void set_state(smc_data_EdgeState s, std::string why);
  // ---- config_intake.cpp: decoded on the comms thread, checked on the
  // intake thread (parsing, validation and the Grafcet's verification never
  // hold up operator commands), applied back on the comms thread.
  void apply_checked_configs();
  void refuse(const std::string& config_id, const std::string& why);
  // The simulated mill that cuts a job of this configuration: the mill's
  // own model (--mill-model) machines the job's part (the configuration's
  // cutter and part geometry, the mill's cutting law and structure), with
  // --break-tooth's breaks. Without --mill-model, the configuration's model.
  // The configuration itself is left as the cell sent it: the edge's modules
  // know the cell's models, never the plant's (module E's vibration
  // estimate uses the configuration's structure, as on a real machine).
  std::unique_ptr<SimulatedMill> simulated_mill(const smc::config::SupervisorConfig& cfg,
                                                double sample_period_s) const;
  // Full check: everything the job would build, built now.
  std::string check(const smc::config::SupervisorConfig& cfg);
  void take_configs();
  // ---- jobs.cpp
  void take_jobs();
  void start_job(const smc::config::JobAssignment& a);
  void report_interrupted(const std::string& job_id, const std::string& why);
  void publish_progress(smc_data_JobPhase phase, const std::string& why);
  bool paced() const { return opt.paced || opt.speedup != 1.0; }
  bool job_running() const;
  void stop_loop();
  void finish_job();
  // ---- operator.cpp
  void take_commands();
  // ---- telemetry.cpp
  void drain();
  void on_event(const EdgeEvent& e);
  // The program after a rewrite or a speed change, on smc_program.
  void publish_program(const EdgeEvent& e);

  // Last member: destroyed (its thread stopped) before everything it uses.
  std::unique_ptr<ConfigIntake> intake;
};

}  // namespace smc::edge
