#pragma once
// Stability lobes by the semi-discretization method (Insperger & Stepan,
// "Semi-discretization method for delayed systems", Int. J. Numer. Meth.
// Engng 55 (2002) 503-518; "Updated semi-discretization method for periodic
// delay-differential equations with discrete delay", 61 (2004) 117-141) on
// the model linearised about its chatter-free cut.
//
// Linearisation: with u = (tool - part) displacement in the plane, a
// vibration changes tooth i's chip by r_i . (u(t) - u(t - tau)), and the
// force on the tool by -(k_r r_i + k_t t_i) times that, where k_t, k_r are
// the tangent (small-signal) cutting stiffnesses dF/dchip at the nominal
// chip f_t cos(theta_i) (DOMAIN.md note 5; cutting.hpp tangent_stiffness).
// Summed over teeth in cut: F_tool = -H(t) (u(t) - u(t - tau)), H(t) a 2x2
// matrix with the tooth period T. The structure's modes give
//   xi' = A xi + B F,  u = C xi.
// Semi-discretization: T is split into m intervals; on each, H is replaced by
// its mean (the current-state term stays in the exponential: A_i = A - B H_i C)
// and the delayed term by the linear interpolation between the two nearest
// grid points (first-order semi-discretization). The resulting map over one
// period (the monodromy matrix, dimension 2 * modes + 2 * m * delay/T) has
// spectral radius < 1 iff the cut is stable. Its dominant eigenvalue is
// found by Arnoldi iteration on the map (no dense matrix is formed), with a
// dense fallback. The method converges as O(1/m^2); by default the radius is
// evaluated with m and 2m intervals and extrapolated (Richardson,
// (4 rho_2m - rho_m) / 3), which for the paper's case is ten times more
// accurate than 3m intervals alone.

#include <array>
#include <complex>
#include <cstdint>
#include <functional>
#include <vector>

#include "smc/machining/model.hpp"

namespace smc::machining {

struct SdmOptions {
  // Intervals per tooth period m; 0: automatic, the largest of min_intervals,
  // intervals_per_mode_period x (highest natural frequency x T) and
  // intervals_in_cut / (fraction of the period a tooth is in cut), at most
  // max_intervals. With extrapolate, m and 2m are used.
  int intervals = 0;
  int min_intervals = 20;
  double intervals_per_mode_period = 6;
  double intervals_in_cut = 8;
  int max_intervals = 300;
  bool extrapolate = true;
  // Depth search range and tolerance.
  double max_depth_mm = 50;
  double relative_tolerance = 1e-3;
};

enum class BoundaryKind : std::uint8_t {
  hopf,  // complex pair crosses the unit circle (quasi-periodic chatter)
  flip,  // -1 (period doubling)
  fold,  // +1
  none,  // stable up to max_depth_mm
};
const char* to_string(BoundaryKind kind) noexcept;

// The critical (dominant) Floquet multiplier of a cut.
struct Multiplier {
  std::complex<double> value;
  double magnitude = 0;
  BoundaryKind kind = BoundaryKind::hopf;  // classified by its angle
};

struct LobePoint {
  double spindle_rpm = 0;
  double critical_depth_mm = 0;  // max_depth_mm when kind == none
  BoundaryKind kind = BoundaryKind::none;
  // Chatter frequency (Hz) in (0, tooth passing frequency / 2]: the base
  // frequency of the critical multiplier, arg(mu) / (2 pi T). The vibration
  // contains it plus every multiple of the tooth passing frequency.
  double base_chatter_frequency_hz = 0;
  int intervals = 0;  // m used (the base count when extrapolating)
};

// Spectral radius and dominant multiplier of the linearised cut (with
// extrapolate, `value` comes from 2m intervals and `magnitude` is the
// extrapolated radius).
Multiplier dominant_multiplier(const MillingModel& model, const CutConditions& cut,
                               const SdmOptions& options = {});

// The m that `options` gives at this speed.
int sdm_intervals(const MillingModel& model, double spindle_rpm, const SdmOptions& options = {});

// The smallest depth at which the linearised cut loses stability at this
// speed: stable just below, unstable just above. Found from 0 upwards by
// growing a bracket and then by the Illinois (modified regula falsi) method
// on |mu| - 1 to relative_tolerance.
LobePoint critical_depth_sdm(const MillingModel& model, double spindle_rpm,
                             double feed_per_tooth_mm, const SdmOptions& options = {});

struct LobeOptions {
  double rpm_min = 0;
  double rpm_max = 0;
  int speeds = 200;              // equally spaced, ends included
  double feed_per_tooth_mm = 0;  // nominal chip for the tangent stiffness (power law)
  SdmOptions sdm;
  // Called after each speed (for progress output); may be empty.
  std::function<void(int done, int total)> on_progress;
};

// The lobe diagram: for each speed the critical depth (continuation from the
// previous speed's boundary, so one lobe diagram costs a few monodromy
// evaluations per speed).
std::vector<LobePoint> stability_lobes(const MillingModel& model, const LobeOptions& options);

// ---------------------------------------------------------------------------
// The general linear periodic problem underneath, for other cutting
// geometries (turning, benchmarks): F_tool(t) = -H(t) (u(t) - u(t - tau)),
// H(t + T) = H(t), tau = delay_periods x T, on the given structure.
struct LinearisedCut {
  Structure structure;
  double period_s = 0;    // T
  int delay_periods = 1;  // tau / T
  // Mean of H over [t0, t1] within [0, T] (N per mm of chip), row-major
  // {H_xx, H_xy, H_yx, H_yy}: force on the tool = -H (u - u_tau).
  std::function<std::array<double, 4>(double t0_s, double t1_s)> mean_directional;
};
// Dominant multiplier with m = intervals (and 2m, extrapolated, if extrapolate).
Multiplier dominant_multiplier(const LinearisedCut& cut, int intervals, bool extrapolate = true);

}  // namespace smc::machining
