#pragma once
// SMC selection and planning for one job. Narrow contract: the planner gets
// the job, its part, tool and machine and the models found for them, never
// the database.

#include <optional>
#include <string>
#include <vector>

#include "smc/cell/store/entities.hpp"
#include "smc_config.pb.h"

namespace smc::cell {

struct PlanInputs {
  store::Job job;
  store::Part part;
  store::Tool tool;
  std::vector<store::ProcessModel> models;  // found for the job's machine(s), tool, material, part
};

struct Selection {
  smc::config::SmcVariant variant = smc::config::SMC_II;
  std::string explanation;                     // which models were found, and why this variant
  std::optional<store::ProcessModel> force;    // validated force-process model (SMC I)
  std::optional<store::ProcessModel> milling;  // validated milling (structural) model (SMC I)
};

// SMC I when a validated force-process model and a validated milling model
// exist for the job's tool and material (and part, when models are part
// specific); SMC II otherwise. The explanation lists every model considered.
Selection select_variant(const PlanInputs& in);

struct Plan {
  smc::config::SupervisorConfig config;  // machine fields left for dispatch
  double critical_depth_mm = -1;  // SMC I: time-domain critical depth at the programmed speed
  double planning_s = 0;
};

class Planner {
 public:
  // `grafcet_dir` holds smc1.grafcet and smc2.grafcet; `defaults` the
  // operation and simulation defaults (cell/configs/defaults.textproto).
  Planner(const std::string& grafcet_dir, smc::config::SupervisorConfig defaults);

  // SMC I: critical depth by time-domain simulation at the programmed speed
  // and feed, passes of equal depth no deeper than `margin` x critical,
  // model-based control. SMC II: one pass at full depth, adaptive control,
  // chatter detection and suppression. Throws std::runtime_error naming
  // what is missing.
  Plan plan(const PlanInputs& in, const Selection& sel) const;

  // Fills in the machine and gives the configuration its id (at dispatch).
  static smc::config::SupervisorConfig for_machine(const smc::config::SupervisorConfig& plan,
                                                   const store::Machine& machine,
                                                   const std::string& config_id);

  double margin = 0.8;  // passes no deeper than 80 % of the critical depth

 private:
  std::string smc1_text_, smc2_text_;
  smc::config::SupervisorConfig defaults_;
};

}  // namespace smc::cell
