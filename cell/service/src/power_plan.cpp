#include "smc/cell/power_plan.hpp"

#include <cmath>
#include <stdexcept>

#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc/supervision/parameters.hpp"

namespace smc::cell {

double power_force_ratio(const smc::config::MillingModel& model, double depth_mm,
                         double spindle_rpm, double feed_per_tooth_mm) {
  const auto m = smc::machining::from_proto(model, "milling_model");
  smc::machining::BatchOptions o;
  o.steady = true;
  o.record_every_s = 0;
  // Ten revolutions: the structure's response to the nominal forces settles.
  o.duration_s = 10 * 60.0 / spindle_rpm;
  const auto r = smc::machining::simulate(m, {spindle_rpm, feed_per_tooth_mm, depth_mm}, o);
  const double v = smc::supervision::cutting_speed_m_s(m.cutter.radius_mm, spindle_rpm);
  if (!(r.max_abs_fy_n > 0) || !(v > 0)) {
    throw std::invalid_argument("the planned cut has no force (depth, feed or speed is 0)");
  }
  return r.mean_power_w / (v * r.max_abs_fy_n);
}

double force_reference_n(const smc::config::SupervisorConfig& c, double max_spindle_power_w,
                         double depth_mm, double spindle_rpm, double feed_per_tooth_mm) {
  const auto& op = c.operation();
  const double target = op.power_target_fraction() > 0 ? op.power_target_fraction() : 0.95;
  const double safety = op.force_safety_factor() > 0 ? op.force_safety_factor() : 1.0;
  const double limit = target * max_spindle_power_w / safety;
  const double rho = power_force_ratio(c.milling_model(), depth_mm, spindle_rpm, feed_per_tooth_mm);
  const double v = smc::supervision::cutting_speed_m_s(op.cutter_radius_mm(), spindle_rpm);
  return limit / (v * rho);
}

void plan_force_references(smc::config::SupervisorConfig& c) {
  // A plan from the part's own cuts has no cutting law to simulate: module
  // M holds the power from the measured spindle power instead.
  if (c.variant() != smc::config::SMC_I || !c.milling_model().has_law()) return;
  const int teeth = static_cast<int>(c.operation().teeth());
  const double power = c.machine().max_spindle_power_w();
  for (auto& pass : *c.mutable_program()->mutable_passes()) {
    const double fpt =
        smc::supervision::feed_per_tooth_mm(pass.feedrate_mm_s(), teeth, pass.spindle_rpm());
    pass.set_force_reference_n(
        force_reference_n(c, power, pass.depth_mm(), pass.spindle_rpm(), fpt));
  }
}

}  // namespace smc::cell
