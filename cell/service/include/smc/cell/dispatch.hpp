#pragma once
// The cell's dispatch and lost-edge decisions as pure functions of what the
// service knows, so they can be tested without DDS or a database. The
// service (service.cpp) gathers the inputs and carries the decisions out.

#include <chrono>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace smc::cell {

// A mill as the cell sees it: from the database and the edge's status.
struct MillView {
  std::string id;
  bool alive = false;  // its smc_edge_status instance is alive
  bool ready = false;  // its edge reports idle or configured (not running, holding, faulted)
};

struct PlannedJob {
  std::string id;
  int64_t priority = 0;    // higher first
  std::string machine_id;  // pinned to this machine; empty: any
  uint32_t attempt = 0;    // attempts so far
};

struct Assignment {
  std::string job_id;
  std::string machine_id;
  uint32_t attempt = 0;  // the attempt this assignment is
};

// Which planned job goes to which mill now: jobs by priority (stable for
// equal priorities, i.e. submission order), each to the first mill in `mills`
// order that is alive, ready, not `busy` and allowed by the job's pin; one
// job per mill.
std::vector<Assignment> choose_assignments(const std::vector<PlannedJob>& planned,
                                           const std::vector<MillView>& mills,
                                           std::set<std::string> busy);

// An assigned or running job on a mill that is not alive is interrupted once
// the mill has been lost for `grace`, counted from when it was lost or from
// the cell's start, whichever is later (an edge not seen since the cell
// started gets the same grace).
bool edge_lost_past_grace(bool alive, std::chrono::steady_clock::time_point lost_since,
                          std::chrono::steady_clock::time_point cell_started,
                          std::chrono::steady_clock::time_point now,
                          std::chrono::milliseconds grace);

// After an interruption: re-queued while attempts remain, else failed.
struct AfterInterruption {
  bool requeue = false;
  std::string reason;
};
AfterInterruption after_interruption(uint32_t attempt, uint32_t max_attempts);

}  // namespace smc::cell
