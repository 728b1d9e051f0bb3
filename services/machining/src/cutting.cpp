#include "smc/machining/cutting.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace smc::machining {

namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;

// 1000 * P(chip, depth, V) * chip * depth: newtons.
double pressure_force_n(const PressureLaw& p, double chip_mm, double depth_mm, double v_m_min) {
  return 1000.0 * p.coefficient_kn_per_mm2 * std::pow(chip_mm, 1.0 + p.feed_exponent) *
         std::pow(depth_mm, 1.0 + p.depth_exponent) * std::pow(v_m_min / 1000.0, p.speed_exponent);
}
}  // namespace

int rotation_sense(const Workpiece& part) noexcept {
  const int part_side = part.offset_mm > 0 ? 1 : -1;
  const int entry_side = part.down_milling ? -part_side : part_side;
  // With theta increasing, the teeth enter the material on the -y side.
  return entry_side < 0 ? 1 : -1;
}

double cutting_speed_m_per_min(double radius_mm, double spindle_rpm) noexcept {
  return 2.0 * kPi * radius_mm * 1e-3 * spindle_rpm;
}

double cutting_speed_m_per_s(double radius_mm, double spindle_rpm) noexcept {
  return cutting_speed_m_per_min(radius_mm, spindle_rpm) / 60.0;
}

Engagement engagement(const Cutter& cutter, const Workpiece& part) noexcept {
  Engagement e;
  const double r = cutter.radius_mm;
  const double lo = part.offset_mm - part.width_mm / 2;
  const double hi = part.offset_mm + part.width_mm / 2;
  if (!(r > 0) || !(hi > lo) || lo >= r || hi <= -r) return e;
  e.engaged = true;
  e.low_rad = std::asin(std::clamp(lo / r, -1.0, 1.0));
  e.high_rad = std::asin(std::clamp(hi / r, -1.0, 1.0));
  const bool increasing = rotation_sense(part) > 0;
  e.entry_rad = increasing ? e.low_rad : e.high_rad;
  e.exit_rad = increasing ? e.high_rad : e.low_rad;
  e.mean_teeth_in_cut = (e.high_rad - e.low_rad) * cutter.teeth / (2.0 * kPi);
  return e;
}

bool in_cut(const Engagement& e, double theta_rad) noexcept {
  if (!e.engaged || !std::isfinite(theta_rad)) return false;
  double t = std::remainder(theta_rad, 2.0 * kPi);  // (-pi, pi]
  return t >= e.low_rad && t <= e.high_rad;
}

ToothLoad tooth_load(const CuttingLaw& law, double lead_angle_deg, double chip_mm, double depth_mm,
                     double cutting_speed_m_min) noexcept {
  ToothLoad load;
  if (!(chip_mm > 0) || !(depth_mm > 0)) return load;
  const double lead = lead_angle_deg * kDegToRad;
  if (const auto* p = std::get_if<PowerLaw>(&law)) {
    if (!(cutting_speed_m_min > 0)) return load;
    load.tangential_n = pressure_force_n(p->cutting, chip_mm, depth_mm, cutting_speed_m_min);
    const double thrust = pressure_force_n(p->thrust, chip_mm, depth_mm, cutting_speed_m_min);
    load.radial_n = thrust * std::cos(lead);
    load.axial_n = thrust * std::sin(lead);
  } else if (const auto* l = std::get_if<LinearLaw>(&law)) {
    const double a_h = depth_mm * chip_mm;
    load.tangential_n = l->k_t_n_per_mm2 * a_h;
    const double thrust = l->k_n_n_per_mm2 * a_h;
    load.radial_n = thrust * std::cos(lead);
    load.axial_n = thrust * std::sin(lead) + l->k_a_n_per_mm2 * a_h;
  }
  return load;
}

CuttingStiffness tangent_stiffness(const CuttingLaw& law, double lead_angle_deg, double chip_mm,
                                   double depth_mm, double cutting_speed_m_min) noexcept {
  CuttingStiffness k;
  if (!(depth_mm > 0)) return k;
  const double lead = lead_angle_deg * kDegToRad;
  if (const auto* p = std::get_if<PowerLaw>(&law)) {
    if (!(chip_mm > 0) || !(cutting_speed_m_min > 0)) return k;
    // d/dh [c h^(1+a) ...] = (1 + a) F / h
    const double ft = pressure_force_n(p->cutting, chip_mm, depth_mm, cutting_speed_m_min);
    const double fn = pressure_force_n(p->thrust, chip_mm, depth_mm, cutting_speed_m_min);
    k.tangential_n_per_mm = (1.0 + p->cutting.feed_exponent) * ft / chip_mm;
    const double kn = (1.0 + p->thrust.feed_exponent) * fn / chip_mm;
    k.radial_n_per_mm = kn * std::cos(lead);
    k.axial_n_per_mm = kn * std::sin(lead);
  } else if (const auto* l = std::get_if<LinearLaw>(&law)) {
    k.tangential_n_per_mm = l->k_t_n_per_mm2 * depth_mm;
    k.radial_n_per_mm = l->k_n_n_per_mm2 * depth_mm * std::cos(lead);
    k.axial_n_per_mm = (l->k_n_n_per_mm2 * std::sin(lead) + l->k_a_n_per_mm2) * depth_mm;
  }
  return k;
}

CutForces static_forces(const MillingModel& model, const CutConditions& cut,
                        double spindle_angle_rad) noexcept {
  CutForces out;
  const Engagement e = engagement(model.cutter, model.workpiece);
  const int n = model.cutter.teeth;
  const double s = rotation_sense(model.workpiece);
  const double v_m_min = cutting_speed_m_per_min(model.cutter.radius_mm, cut.spindle_rpm);
  // Runout in mm, when every tooth has a value (validated models do; at most
  // 1000 teeth, model_proto.cpp).
  double runout_mm[1000];
  const bool runout = has_runout(model.cutter) &&
                      static_cast<int>(model.cutter.radial_runout_um.size()) == n && n <= 1000;
  for (int i = 0; runout && i < n; ++i) {
    runout_mm[i] = 1e-3 * model.cutter.radial_runout_um[static_cast<size_t>(i)];
  }
  for (int i = 0; i < n; ++i) {
    const double theta = spindle_angle_rad + 2.0 * kPi * i / n;
    if (!in_cut(e, theta)) continue;
    const double c = std::cos(theta);
    const double sn = std::sin(theta);
    const double chip = runout ? runout_chip_mm(runout_mm, n, i, cut.feed_per_tooth_mm, c)
                               : cut.feed_per_tooth_mm * c;
    const ToothLoad load =
        tooth_load(model.law, model.cutter.lead_angle_deg, chip, cut.depth_mm, v_m_min);
    if (load.tangential_n <= 0 && load.radial_n <= 0) continue;
    out.fx_n += -load.radial_n * c + s * load.tangential_n * sn;
    out.fy_n += -load.radial_n * sn - s * load.tangential_n * c;
    out.fz_n += load.axial_n;
    out.torque_n_m += load.tangential_n * model.cutter.radius_mm * 1e-3;
    ++out.teeth_in_cut;
  }
  out.power_w = out.torque_n_m * 2.0 * kPi * cut.spindle_rpm / 60.0;
  return out;
}

CutForces mean_static_forces(const MillingModel& model, const CutConditions& cut,
                             int samples) noexcept {
  CutForces mean;
  samples = std::max(samples, 1);
  // One tooth pitch repeats the cut; with runout, only a revolution does.
  const double pitch =
      has_runout(model.cutter) ? 2.0 * kPi : 2.0 * kPi / std::max(model.cutter.teeth, 1);
  double teeth = 0;
  for (int j = 0; j < samples; ++j) {
    const CutForces f = static_forces(model, cut, pitch * (j + 0.5) / samples);
    mean.fx_n += f.fx_n;
    mean.fy_n += f.fy_n;
    mean.fz_n += f.fz_n;
    mean.power_w += f.power_w;
    mean.torque_n_m += f.torque_n_m;
    teeth += f.teeth_in_cut;
  }
  mean.fx_n /= samples;
  mean.fy_n /= samples;
  mean.fz_n /= samples;
  mean.power_w /= samples;
  mean.torque_n_m /= samples;
  mean.teeth_in_cut = static_cast<int>(std::lround(teeth / samples));
  return mean;
}

}  // namespace smc::machining
