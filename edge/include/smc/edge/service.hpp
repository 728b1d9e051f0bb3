#pragma once
// The edge process on DDS (smc-edge run): receives its configuration and job
// assignments from the cell, runs each job in the real-time loop on the
// simulated mill, and publishes what the cell and dashboards need.
//
//   in:  smc_config (SupervisorConfig, key = machine id), smc_job
//        (JobAssignment), smc_operator_command (OperatorCommand)
//   out: smc_force_summary, smc_force_batch, smc_chatter_event,
//        smc_supervisor_situation, smc_edge_status (liveliness lease),
//        smc_job_progress, smc_program (every part-program rewrite)
//
// A configuration is checked in full (parameters, program limits, Grafcet
// parsed and verified, the mill's model) before it is accepted; a bad one is
// reported on smc_edge_status and the last good one stays in force. A job
// starts only under an accepted configuration whose id it names, and each
// (job, attempt) runs at most once in the life of the process. The comms
// thread is the caller's; the loop thread never touches DDS.
//
// Boundary policy. Input from outside (documents, assignments, commands) is
// checked where it enters: a bad one is logged, reported on smc_edge_status
// and dropped, and nothing accepted before is lost; a job never runs under
// an unchecked configuration. A command for another machine is ignored.
// Operator commands are served before any other reader on every wake-up.
// A DDS failure (DdsError: the participant or a topic cannot be created or
// written) ends run() with the exception: the process exits non-zero and
// its supervisor (systemd, the container runtime) restarts it; the journal
// makes sure a half-cut job is reported interrupted, never cut again.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace smc::edge {

struct ServiceOptions {
  std::string machine_id;
  uint32_t domain_id = 0;
  std::string partition;                  // DDS partition (tests isolate themselves)
  std::chrono::milliseconds lease{2000};  // liveliness lease of smc_edge_status
  int batch_decimation = 1;               // raw force: every n-th sample
  double speedup = 1.0;                   // machine seconds per wall second
  // Paced simulation instead of the real-time loop: a plain thread keeps
  // machine time at `speedup` x wall time and catches up after a delay
  // (no deadlines, so no overrun holds). Always so when speedup != 1.
  bool paced = false;
  bool realtime = true;  // SCHED_FIFO, mlockall when permitted
  // A tick this late is an overrun, which holds the feed (real-time loop).
  std::chrono::microseconds overrun_threshold{2000};
  std::string mill_model_file;  // the mill's own model; default: the config's
  // The simulated mill's tool breaks, applied to every job it cuts (machine
  // time from the job's start): what a test needs to see module N stop a
  // job in a whole cell.
  struct ToothBreak {
    unsigned tooth = 0;       // from 1
    double at_s = 0;          // machine time from the job's start
    double edge_loss_mm = 0;  // 0: the whole edge
  };
  std::vector<ToothBreak> tooth_breaks;
  // Journal of the (job, attempt)s this edge has started, kept across
  // restarts: an assignment started by an earlier run of the process is not
  // run again but reported interrupted, so the cell re-queues it. Empty:
  // remembered in memory only.
  std::string state_file;
  // The machine: "sim" (the simulated mill, default) or "linuxcnc" (the
  // running LinuxCNC, linuxcnc_drive.hpp: its servo records pace the loop).
  std::string drive = "sim";
  std::string program_dir = "/tmp/smc-programs";  // G-code handed to LinuxCNC
};

class EdgeService {
 public:
  explicit EdgeService(ServiceOptions options);
  ~EdgeService();
  EdgeService(const EdgeService&) = delete;
  EdgeService& operator=(const EdgeService&) = delete;

  // Runs until `stop` becomes true. Returns the process exit code.
  int run(const std::atomic<bool>& stop);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::edge
