#pragma once
// TEST TOOL, not part of the product. Publishes on DDS what N edges and the
// cell would, at wall-clock pace (one revolution = 40 ms at 1500 rpm), so the
// dashboard can be developed and tested end to end before the real edge and
// cell processes exist:
//
//   * per mill: SupervisorConfig (smc_config) with the shipped Grafcet
//     (cell/grafcets/smc2.grafcet or smc1.grafcet), PartProgram (smc_program)
//     on every rewrite, ForceSummary and ForceBatch every revolution,
//     SupervisorSituation whenever the Grafcet (run by smc_grafcet's Engine on
//     inputs a..e) changes, EdgeStatus, JobProgress, ChatterEvent;
//   * per job: JobStatus documents (smc_job_status), as the cell would.
//
// It obeys OperatorCommand: feed hold on -> input a = 1 (step 5, module C),
// off -> a = 0, chatter signal -> a pulse on input c. Forces follow the
// paper's pattern (see DOMAIN.md), not its physics: an SMC II mill's first
// 2 mm pass chatters, is detected, and the program is rewritten to two 1 mm
// passes; an SMC I mill runs two planned 1 mm passes without chatter.

#include <atomic>
#include <cstdint>
#include <string>

namespace smc::dashboard::testing {

struct FakeCellOptions {
  int mills = 1;
  std::string prefix = "mill-";  // mills are <prefix>1 .. <prefix>N
  std::uint32_t domain_id = 0;
  std::string partition;
  std::string grafcet_dir;  // holds smc1.grafcet and smc2.grafcet
  std::uint64_t seed = 1;
  double duration_s = 0;  // 0: until stopped
  bool all_smc2 = false;  // default: odd mills SMC II, even mills SMC I
  double part_length_mm = 40;
};

// Runs until `stop` is set (or the duration passes). Prints one line per
// operator command received on stdout ("command MILL ACTION OPERATOR ID").
// Returns 0, or throws on a set-up failure (Grafcet unreadable, DDS).
int run_fake_cell(const FakeCellOptions& options, const std::atomic<bool>& stop);

}  // namespace smc::dashboard::testing
