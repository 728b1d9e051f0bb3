#pragma once
// Cutting forces without vibration: the pressure laws (A1, A2), a tooth's
// forces (A3, A4 and the axial force), the engagement (entry and exit angles,
// the immersion function A5), the spindle power, and the small-signal cutting
// stiffness the stability analysis linearises with.
//
// Tooth angle theta: from +x (the feed) towards +y, tooth tip at
// R (cos theta, sin theta) from the cutter axis. The nominal chip of a tooth
// is the feed per tooth projected on its radial direction, f_t cos(theta).
//
// Forces on the TOOL from one tooth (the part feels the opposite):
//
//   F = -F_r r - F_t t,   r = (cos theta, sin theta),  t = s (-sin theta, cos theta)
//   F_x = -F_r cos theta + s F_t sin theta
//   F_y = -F_r sin theta - s F_t cos theta
//   F_z = F_a  (> 0 pushes the tool away from the part)
//
// with s = rotation_sense() (+1: theta grows with time) and
//   F_t = P_C f d                (tangential, opposes the tooth's motion)
//   F_r = P_T f d cos(psi_r)     (radial, pushes the tool off the material)
//   F_a = P_T f d sin(psi_r)     (axial; DOMAIN.md note 3)
// For s = +1 these are the paper's A3 and A4 term by term.

#include <span>

#include "smc/machining/model.hpp"

namespace smc::machining {

// +1 if theta increases with time, -1 if it decreases (see Workpiece::down_milling).
int rotation_sense(const Workpiece& part) noexcept;

// Cutting speed at the cutter periphery, V = 2 pi R n.
double cutting_speed_m_per_min(double radius_mm, double spindle_rpm) noexcept;
double cutting_speed_m_per_s(double radius_mm, double spindle_rpm) noexcept;

// The range of tooth angles over which the tip is over the part's width band
// on the leading half of the cutter (cos theta > 0): theta in [entry, exit]
// when the teeth turn with theta increasing, [exit, entry] reversed. Angles in
// (-pi/2, pi/2]; `engaged` is false when the band misses the cutter.
struct Engagement {
  bool engaged = false;
  double low_rad = 0;    // smallest theta in cut
  double high_rad = 0;   // largest theta in cut
  double entry_rad = 0;  // where a tooth enters the material
  double exit_rad = 0;   // where it leaves
  // Average number of teeth in cut, (high - low) N / (2 pi).
  double mean_teeth_in_cut = 0;
};
Engagement engagement(const Cutter& cutter, const Workpiece& part) noexcept;

// The immersion function g(theta) (A5): 1 if a tooth at theta (any real) is
// in the engagement range, else 0.
bool in_cut(const Engagement& e, double theta_rad) noexcept;

// Forces from one tooth's chip, in the tooth's own directions (N).
struct ToothLoad {
  double tangential_n = 0;  // F_t
  double radial_n = 0;      // F_r = thrust cos(psi_r)
  double axial_n = 0;       // F_a
};
// Chip and depth in mm, cutting speed in m/min. Zero for chip <= 0 or depth <= 0.
ToothLoad tooth_load(const CuttingLaw& law, double lead_angle_deg, double chip_mm, double depth_mm,
                     double cutting_speed_m_min) noexcept;

// Small-signal (tangent) cutting stiffness d F / d chip at a nominal chip
// (N per mm of chip): what a linearised stability analysis must use for a
// power law (DOMAIN.md note 5). For the linear law it is K a (no chip needed).
struct CuttingStiffness {
  double tangential_n_per_mm = 0;
  double radial_n_per_mm = 0;
  double axial_n_per_mm = 0;
};
CuttingStiffness tangent_stiffness(const CuttingLaw& law, double lead_angle_deg, double chip_mm,
                                   double depth_mm, double cutting_speed_m_min) noexcept;

// Forces on the tool with no vibration, every tooth in the engagement cutting
// its nominal chip f_t cos(theta_i): theta_i = spindle_angle + i 2 pi / N.
// Power is sum F_t V (W); torque sum F_t R (N m).
struct CutForces {
  double fx_n = 0;
  double fy_n = 0;
  double fz_n = 0;
  double power_w = 0;
  double torque_n_m = 0;
  int teeth_in_cut = 0;
};
CutForces static_forces(const MillingModel& model, const CutConditions& cut,
                        double spindle_angle_rad) noexcept;
// Mean of static_forces over a tooth period (a revolution with runout;
// `samples` equally spaced angles).
CutForces mean_static_forces(const MillingModel& model, const CutConditions& cut,
                             int samples = 3600) noexcept;

}  // namespace smc::machining
