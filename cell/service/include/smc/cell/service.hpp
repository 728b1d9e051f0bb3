#pragma once
// The cell service (smc-cell serve): jobs from the database are selected
// (SMC I or II, with an explanation), planned, configured, verified and
// dispatched to idle mills over DDS; their progress is tracked and every
// state change persisted. See cell/README.md for the job policy.
//
// Boundary policy. A job that cannot be planned or whose configuration does
// not validate is marked failed with the reason, and the cell goes on. Edge
// reports that name an unknown job or another machine are ignored;
// malformed documents are dropped by the transport's checks. A database or
// DDS failure (StoreError, DdsError) ends run() with the exception: the
// process exits non-zero and is restarted by its supervisor; everything the
// cell accepted is in the database and is resumed on restart.

#include <atomic>
#include <chrono>
#include <memory>
#include <string>

namespace smc::cell {

struct ServiceOptions {
  std::string db_path;
  std::string grafcet_dir;    // smc1.grafcet, smc1_guarded.grafcet, smc2.grafcet
  std::string defaults_file;  // cell/configs/defaults.textproto
  uint32_t domain_id = 0;
  std::string partition;
  // An edge whose status has not been alive for this long after the cell
  // starts, or whose liveliness is lost, interrupts its job.
  std::chrono::milliseconds edge_grace{6000};
  uint32_t max_attempts = 3;  // an interrupted job is re-queued until this many attempts
  bool learn = true;          // fit force-process models from SMC II runs
  // SMC I jobs run smc1_guarded (chatter detector as a safety net; chatter
  // marks the plan's models suspect); false: the paper's SMC I.
  bool guard_smc1 = true;
};

class CellService {
 public:
  explicit CellService(ServiceOptions options);
  ~CellService();
  CellService(const CellService&) = delete;
  CellService& operator=(const CellService&) = delete;
  // Serves until `stop`; returns 0, or kRejoinDds when the process was
  // frozen (suspended, paused) for longer than half its DDS participant
  // lease: its peers may have dropped its participant while it still holds
  // theirs, and under DDS Security such a one-sided loss is not healed by
  // Cyclone DDS 0.10 (eclipse-cyclonedds/cyclonedds#1895). The caller then
  // makes a new CellService, which joins with a new participant, as a
  // restarted cell would.
  int run(const std::atomic<bool>& stop);
  static constexpr int kRejoinDds = 75;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::cell
