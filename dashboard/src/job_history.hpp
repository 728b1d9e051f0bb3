#pragma once
// A finished (or running) job's history for the engineer's views, read from
// the cell's database (not the dashboard's memory: it outlives the job and a
// dashboard restart): the plan and why, the state changes and notes, the
// programs as run, and every revolution the cell recorded.

#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace smc::cell::store {
class Store;
}

namespace smc::dashboard {

class JobHistory {
 public:
  // The cell's database (smc-cell serve's --db), opened on the first request
  // (the dashboard may start before the cell has created it); a request it
  // cannot open it for throws with the file and the fix.
  explicit JobHistory(std::string db_path);
  ~JobHistory();

  // GET /api/jobs/ID/history: nullopt for an unknown job.
  std::optional<std::string> json(const std::string& job_id);
  // GET /api/jobs/ID/history.csv: one row per recorded revolution.
  std::optional<std::string> csv(const std::string& job_id);
  // GET /api/jobs/ID/lobes: the stability lobes of an SMC I plan's
  // structural model (semi-discretization, 0.5-2 x the planned speed) with
  // the planned speed and depth per pass; {"lobes": null, "why"} for a job
  // without one. nullopt for an unknown job.
  std::optional<std::string> lobes(const std::string& job_id);

 private:
  cell::store::Store& db();  // under mu_
  std::string path_;
  std::mutex mu_;  // the store is one connection: one request at a time
  std::unique_ptr<cell::store::Store> db_;
};

}  // namespace smc::dashboard
