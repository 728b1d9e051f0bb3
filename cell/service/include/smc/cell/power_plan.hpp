#pragma once
// The SMC I plan's force reference from the models: F_ref for each pass such
// that the planned cut's mean spindle power is the share of the machine's
// limit that the edge's spindle power monitor (module M) holds.

#include "smc_config.pb.h"

namespace smc::cell {

// The cut's ratio rho = mean spindle power / (V max |F_y|), from a steady
// time-domain run of the milling model at the pass's depth, speed and feed
// per tooth (nominal chip: the plan is chatter-free). Throws
// std::invalid_argument / ModelError for a bad model or cut.
double power_force_ratio(const smc::config::MillingModel& model, double depth_mm,
                         double spindle_rpm, double feed_per_tooth_mm);

// The force reference of one SMC I pass on a machine of this power: target x
// P_max / safety / (V rho), target being operation.power_target_fraction
// (0: the edge's default 0.95). Needs the configuration's milling model and
// operation (cutter radius).
double force_reference_n(const smc::config::SupervisorConfig& config, double max_spindle_power_w,
                         double depth_mm, double spindle_rpm, double feed_per_tooth_mm);

// Sets program.passes[i].force_reference_n of an SMC I configuration whose
// machine is filled in (force_reference_n for each pass). Leaves other
// variants, and configurations whose milling model has no cutting law (an
// SMC I plan from the part's own cuts), as they are.
void plan_force_references(smc::config::SupervisorConfig& config);

}  // namespace smc::cell
