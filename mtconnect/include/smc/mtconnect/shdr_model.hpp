#pragma once
// The cell's mills as MTConnect devices: what the SMC's DDS topics say,
// turned into SHDR observations (the adapter protocol MTConnect agents read;
// README.md). One device per mill, named by its machine id; every key is
// "<machine>:<data item>" (the agent's device-prefixed form, so one adapter
// serves every mill). Each on_* returns the lines to send now (only what
// changed); snapshot() gives every current value, for an agent that has
// just connected.
//
// Data items of each mill (devices_xml() declares them for the agent):
//   avail        AVAILABILITY     AVAILABLE while the mill's edge is alive
//   exec         EXECUTION        READY, ACTIVE, FEED_HOLD, INTERRUPTED,
//                                 PROGRAM_COMPLETED
//   program      PROGRAM          the job in the machine
//   block        BLOCK            "pass 2 of 3" (the pass being cut)
//   smc          PROGRAM_COMMENT  the supervisor in force (SMC I, SMC II)
//   Srpm         ROTARY_VELOCITY  spindle speed (rev/min)
//   path_feedrate PATH_FEEDRATE   commanded feedrate (mm/s)
//   feed_ovr     PATH_FEEDRATE_OVERRIDE  commanded / programmed (%)
//   Fy           x:FORCE-like SAMPLE type FORCE (N): F_Y per revolution
//   power        WATTAGE          spindle power (W; UNAVAILABLE when the
//                                 drive has no power signal)
//   chatter      CONDITION SYSTEM WARNING while chatter is being suppressed
//                                 (native code CHATTER_AUTOMATIC or
//                                 CHATTER_OPERATOR), NORMAL again once the
//                                 edge cuts without it
//   edge_fault   CONDITION SYSTEM FAULT while the edge holds the feed on a
//                                 fault (native code EDGE_FAULT, the reason)
//
// Timestamps are the DDS source timestamps of the samples (the edge's clock
// when it wrote them), so an agent's observations carry the event's time.
// Not thread-safe: one thread owns it.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

struct smc_data_ForceSummary;
struct smc_data_ChatterEvent;
struct smc_data_SupervisorSituation;
struct smc_data_EdgeStatus;
struct smc_data_JobProgress;
namespace smc::config {
class SupervisorConfig;
class PartProgram;
}  // namespace smc::config

namespace smc::mtconnect {

// "2026-11-24T22:17:20.123456Z" for a Unix time in ns.
std::string shdr_time(std::int64_t unix_ns);

class ShdrModel {
 public:
  // Samples (Srpm, path_feedrate, feed_ovr, Fy, power) of one mill are sent
  // at most once per `sample_period_ns` (the latest value); events and
  // conditions at once.
  explicit ShdrModel(std::int64_t sample_period_ns = 100'000'000);

  std::vector<std::string> on_status(const smc_data_EdgeStatus& s, std::int64_t t_ns);
  std::vector<std::string> on_gone(const std::string& machine_id, std::int64_t t_ns);
  std::vector<std::string> on_situation(const smc_data_SupervisorSituation& s, std::int64_t t_ns);
  std::vector<std::string> on_summary(const smc_data_ForceSummary& s, std::int64_t t_ns);
  std::vector<std::string> on_chatter(const smc_data_ChatterEvent& e, std::int64_t t_ns);
  std::vector<std::string> on_progress(const smc_data_JobProgress& p, std::int64_t t_ns);
  std::vector<std::string> on_config(const std::string& machine_id,
                                     const smc::config::SupervisorConfig& c, std::int64_t t_ns);
  std::vector<std::string> on_program(const std::string& machine_id,
                                      const smc::config::PartProgram& p, std::int64_t t_ns);

  // Every current value of every mill, one line each, stamped `now_ns`.
  std::vector<std::string> snapshot(std::int64_t now_ns) const;
  std::vector<std::string> machines() const;

 private:
  struct Mill {
    std::string id;
    std::map<std::string, std::string> current;  // item -> what follows the key
    bool alive = false;
    int state = -1;  // smc_data_EdgeState; -1: not heard of
    bool hold = false;
    int last_phase = -1;  // smc_data_JobPhase of the last job; -1: none
    std::string job_id;
    std::vector<double> programmed_mm_s;  // per pass
    // Chatter: the machine time of the event being suppressed (0: none).
    std::uint64_t chatter_at_ns = 0;
    // Samples: the latest, sent at most every sample period.
    std::map<std::string, std::string> pending;
    std::int64_t last_samples_ns = 0;
  };
  Mill& mill(const std::string& id);
  void set(Mill& m, const std::string& item, const std::string& value, std::int64_t t_ns,
           std::vector<std::string>& out);
  void set_exec(Mill& m, std::int64_t t_ns, std::vector<std::string>& out);

  std::int64_t sample_period_ns_;
  std::map<std::string, Mill> mills_;
};

// The agent's device file for these mills (MTConnect 2.0 Devices.xml).
std::string devices_xml(const std::vector<std::string>& machine_ids);

}  // namespace smc::mtconnect
