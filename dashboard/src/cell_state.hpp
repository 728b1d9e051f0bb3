#pragma once
// What the dashboard knows of the cell: per mill the latest of every live
// topic, a window of F_Y history with the supervisor's situation changes
// (for the chart's marks), the last raw revolutions and chatter events; the
// jobs; the operator commands sent. The DDS thread records samples (each
// on_* returns the stream events to broadcast); HTTP handlers read JSON
// snapshots. One mutex; no call holds it for longer than one copy.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "command.hpp"
#include "event.hpp"

struct smc_data_ForceSummary;
struct smc_data_ForceBatch;
struct smc_data_ChatterEvent;
struct smc_data_SupervisorSituation;
struct smc_data_EdgeStatus;
struct smc_data_JobProgress;
namespace smc::config {
class SupervisorConfig;
class PartProgram;
class JobStatus;
class CatalogView;
}  // namespace smc::config

namespace smc::dashboard {

struct StateLimits {
  std::size_t history_revolutions = 3000;  // F_Y points per mill (2 min at 1500 rpm)
  std::size_t batches = 8;                 // raw revolutions per mill
  std::size_t situations = 2000;           // supervisor situations per mill
  std::size_t chatter_events = 200;        // per mill
  std::size_t jobs = 500;                  // finished jobs are forgotten first
  std::size_t mills = 256;                 // samples of further mills are ignored
  std::size_t commands = 200;              // operator commands remembered
};

class CellState {
 public:
  explicit CellState(StateLimits limits = {});
  ~CellState();
  CellState(const CellState&) = delete;
  CellState& operator=(const CellState&) = delete;

  // ---- recording (DDS thread). `src_unix_ns` is the sample's DDS source
  // timestamp (the writer's wall clock), carried to the browser for latency.
  std::vector<Event> on_summary(const smc_data_ForceSummary& s, std::int64_t src_unix_ns);
  std::vector<Event> on_batch(const smc_data_ForceBatch& b, std::int64_t src_unix_ns);
  std::vector<Event> on_situation(const smc_data_SupervisorSituation& s, std::int64_t src_unix_ns);
  std::vector<Event> on_status(const smc_data_EdgeStatus& s);
  // The edge's status instance lost its writers (process gone) or was disposed.
  std::vector<Event> on_edge_gone(const std::string& machine_id);
  std::vector<Event> on_chatter(const smc_data_ChatterEvent& e);
  std::vector<Event> on_progress(const smc_data_JobProgress& p);
  std::vector<Event> on_config(const std::string& machine_id, const config::SupervisorConfig& c);
  std::vector<Event> on_program(const std::string& machine_id, const config::PartProgram& p);
  std::vector<Event> on_job(const std::string& job_id, const config::JobStatus& j);
  std::vector<Event> on_command(const CommandRecord& record);
  // The cell's catalog and its choice for each part (one document, the latest).
  std::vector<Event> on_catalog(const config::CatalogView& view);

  // ---- reading (any thread): JSON documents of the REST API.
  bool has_mill(const std::string& machine_id) const;
  std::vector<std::string> mill_ids() const;
  std::string mills_json() const;  // array of mill states
  std::optional<std::string> mill_json(const std::string& machine_id) const;  // with details
  std::optional<std::string> history_json(const std::string& machine_id, double seconds) const;
  std::optional<std::string> config_json(const std::string& machine_id) const;
  std::optional<std::string> grafcet_json(const std::string& machine_id) const;
  std::string jobs_json(const std::string& machine_id = {}) const;     // empty: all
  std::string chatter_json(const std::string& machine_id = {}) const;  // empty: all
  std::string commands_json() const;
  // {"view": the CatalogView (null before the cell sent one), "mills": the
  // live state of every mill seen}: machines with their live state, parts
  // with their models and the SMC they would get and why.
  std::string catalog_json() const;
  // Everything a page needs to start: {"mills": [...], "jobs": [...], "commands": [...]}.
  std::string cell_json() const;

  struct Counters {
    std::uint64_t samples = 0;  // data-plane samples and documents recorded
    std::uint64_t ignored = 0;  // past the mill limit
  };
  Counters counters() const;

 private:
  struct Mill;
  struct Job;
  struct Impl;
  // Makes `config_id` the mill's configuration in force, if its document has
  // been seen (caller holds the lock).
  void adopt_config(Mill& m, const std::string& config_id, std::vector<Event>& events);
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::dashboard
