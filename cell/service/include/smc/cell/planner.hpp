#pragma once
// SMC selection and planning for one job. Narrow contract: the planner gets
// the job, its part, tool and machine and the models found for them, never
// the database.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "smc/cell/learning.hpp"
#include "smc/cell/store/entities.hpp"
#include "smc_config.pb.h"

namespace smc::cell {

struct PlanInputs {
  store::Job job;
  store::Part part;
  store::Tool tool;
  std::vector<store::ProcessModel> models;  // found for `machine`, the tool, material and part
  // The machine the plan is for (its models, its limits). An empty id: any
  // machine (an SMC II plan for a job that names none).
  store::Machine machine;
  // What the part's cuts showed on `machine` with the job's tool at the
  // job's speed (learning.hpp), if anything.
  std::optional<StabilityBound> bound;
};

// A machine the cell could plan a job for, with the models found for it.
struct MachineModels {
  store::Machine machine;
  // Its edge is seen, or not yet given up (the cell's edge grace): machines
  // that are available are preferred when several qualify.
  bool available = true;
  std::vector<store::ProcessModel> models;
  std::optional<StabilityBound> bound;  // the part's cuts on it at the job's tool and speed
};

struct Selection {
  smc::config::SmcVariant variant = smc::config::SMC_II;
  std::string explanation;                     // which models were found, and why this variant
  std::optional<store::ProcessModel> force;    // validated force-process model (SMC I)
  std::optional<store::ProcessModel> milling;  // validated milling (structural) model (SMC I)
  // SMC I without a milling model: the part's own cuts at the job's speed
  // on the machine (a chatter-free depth over 20 revolutions or more, and no
  // chatter at or below it). Passes no deeper than that depth.
  std::optional<StabilityBound> bound;
};

// SMC I when a validated, unsuspected force-process model exists for the
// job's tool and material (and part, when models are part specific) on
// in.machine, with a validated milling model or, failing one, a usable
// stability bound from the part's own cuts (in.bound); else SMC II+ when the part allows a spindle
// speed change and in.machine can override its spindle speed; SMC II otherwise. The explanation
// names the machine, lists every model considered (suspect ones with the reason) and says why not
// SMC II+ when the part allows it.
Selection select_variant(const PlanInputs& in);

// Whether a drive has a spindle speed override (module O): the simulated
// mill and the LinuxCNC drive have.
bool drive_overrides_spindle_speed(const std::string& drive);
// Whether module O can move this machine's spindle: its drive has the
// override and its speed range is more than 2 % wide (not a fixed-speed
// spindle).
bool machine_can_change_spindle_speed(const store::Machine& m);

// Binds the job to a machine and selects its variant: the job's own machine
// when it names one; else the first available machine (in the given order)
// whose models allow SMC I (when none is available, the first with such
// models); else, when the part allows a speed change, SMC II+ on the first
// available machine that can override its spindle speed; else SMC II for
// any machine, the explanation giving each machine's reason. Fills
// in.machine and in.models.
Selection bind_and_select(PlanInputs& in, const std::vector<MachineModels>& machines);

struct Plan {
  smc::config::SupervisorConfig config;  // machine fields left for dispatch
  double critical_depth_mm = -1;  // SMC I: time-domain critical depth at the programmed speed
  double planning_s = 0;
  std::string machine_id;              // SMC I: the machine whose models it used; SMC II+: the
                                       // machine whose spindle it moves; else empty
  std::vector<std::string> model_ids;  // the models it used
  // SMC I: the feeds the stability check covered (mm/tooth): the programmed
  // feed, the eq. 1 equilibrium feed at the pass's F_ref, and the lower
  // clamp the plan gives the controller.
  double programmed_feed_mm = 0, equilibrium_feed_mm = 0, lower_clamp_mm = 0;
};

struct PlannerOptions {
  double margin = 0.8;  // passes no deeper than 80 % of the critical depth
  // SMC I jobs run smc1_guarded.grafcet (SMC I with the chatter detector as
  // a safety net); false: the paper's smc1.grafcet, which has none.
  bool guard_smc1 = true;
  // The lower clamp on the controller's feed is raised at most to this share
  // of the steady feed before a pass is added instead.
  double max_clamp_share = 0.8;
  // The identification segment of a job-shop run of a part with no
  // validated force model: F_ref x each level for this many revolutions
  // (0: none). cell/README.md, "Learning and promotion".
  std::vector<double> identification_levels{0.6, 0.8};
  std::uint32_t identification_revolutions = 15;
};

class Planner {
 public:
  // `grafcet_dir` holds smc1.grafcet, smc1_guarded.grafcet and
  // smc2.grafcet; `defaults` the operation and simulation defaults
  // (cell/configs/defaults.textproto).
  Planner(const std::string& grafcet_dir, smc::config::SupervisorConfig defaults,
          PlannerOptions options = {});

  // SMC I (for in.machine): critical depth by time-domain simulation at the
  // programmed speed and feed, passes of equal depth no deeper than
  // `margin` x critical; then each pass is checked at the feeds the
  // model-based controller may command on that machine: stable with the
  // margin at the eq. 1 equilibrium feed for its power-limited F_ref, and
  // stable (no margin) down to the controller's lower feed clamp, which is
  // raised for that up to max_clamp_share x the steady feed; passes are added
  // until both hold. SMC II: one pass at full depth, adaptive control,
  // chatter detection and suppression. Throws std::runtime_error naming
  // what is missing.
  Plan plan(const PlanInputs& in, const Selection& sel) const;

  // The id of the configuration an attempt of a job runs under:
  // "<job>-a<attempt>".
  static std::string config_id(const store::Job& job, uint32_t attempt) {
    return job.id + "-a" + std::to_string(attempt);
  }
  // Fills in the machine and gives the configuration its id (at dispatch).
  // A plan whose supervisor runs module E with no structure in y (SMC II,
  // SMC II+, SMC I from the part's cuts) gets the whole structure of
  // `structure` (structure_model, candidates.hpp: that machine's), the
  // part's modes too where that model is another part's; its explanation
  // names the model and whose part modes they are, or says that E judges
  // the force spectrum alone where `structure` is null.
  static smc::config::SupervisorConfig for_machine(const smc::config::SupervisorConfig& plan,
                                                   const store::Machine& machine,
                                                   const std::string& config_id,
                                                   const store::ProcessModel* structure = nullptr);
  // What for_machine gives module E, for the job's history at dispatch:
  // "module E with the structure of model ID", "module E on the force
  // spectrum alone (...)", or empty where the plan brings its own structure
  // or runs no E.
  static std::string structure_note(const smc::config::SupervisorConfig& plan,
                                    const store::ProcessModel* structure);

  const PlannerOptions& options() const noexcept { return options_; }

 private:
  std::string smc1_text_, smc1_guarded_text_, smc2_text_, smc2_plus_text_;
  smc::config::SupervisorConfig defaults_;
  PlannerOptions options_;
};

}  // namespace smc::cell
