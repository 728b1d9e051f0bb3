#pragma once
// The integration core shared by the stepping simulator and the batch runs
// (internal). One internal step of length h:
//
//   1. predict the relative displacement u = tool - part at the step's
//      middle (exact half-step of the modes, force held at the previous
//      step's value),
//   2. read u one delay earlier from the history of mid-step values (linear
//      interpolation between stored steps) and store the new one,
//   3. every tooth whose tip is over material cuts the chip
//        h_i = f_t cos(theta_i) + (u_mid - u_delayed) . (cos theta_i, sin theta_i)
//      clipped at zero, with its angle at the step's middle (with runout,
//      f_t cos(theta_i) is runout_chip_mm: model.hpp),
//   4. the force sum is held over the step and the modes advance exactly.
//
// Evaluating the force at the middle of the step makes the scheme second
// order in h for smooth forcing (first order only at the instants a tooth
// enters or leaves the material). Nothing here allocates after construction.

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "fast_pow.hpp"
#include "smc/machining/cutting.hpp"
#include "smc/machining/model.hpp"
#include "smc/machining/structure.hpp"

namespace smc::machining::detail {

struct StepForces {
  double fx_n = 0, fy_n = 0, fz_n = 0;
  double tangential_sum_n = 0;  // sum of F_t (power = this x V)
  int teeth_cutting = 0;
  bool jumped_out = false;  // a tooth with nominal chip >= f_t / 2 cut nothing
};

class CutEngine {
 public:
  // history_capacity: number of mid-step values kept (> longest delay in steps
  // + 2); rounded up to a power of two.
  CutEngine(const MillingModel& model, double step_s, std::size_t history_capacity)
      : structure_(model.structure, step_s),
        history_(2 * std::bit_ceil(history_capacity), 0.0),
        capacity_(static_cast<std::int64_t>(std::bit_ceil(history_capacity))),
        mask_(capacity_ - 1),
        radius_mm_(model.cutter.radius_mm),
        length_mm_(model.workpiece.length_mm),
        band_lo_mm_(model.workpiece.offset_mm - model.workpiece.width_mm / 2),
        band_hi_mm_(model.workpiece.offset_mm + model.workpiece.width_mm / 2),
        teeth_(model.cutter.teeth),
        offset_cos_(static_cast<std::size_t>(model.cutter.teeth)),
        offset_sin_(static_cast<std::size_t>(model.cutter.teeth)),
        runout_mm_(static_cast<std::size_t>(model.cutter.teeth), 0.0),
        has_runout_(has_runout(model.cutter)),
        sense_(rotation_sense(model.workpiece)),
        sense_d_(sense_),
        law_(model.law),
        pow_(feed_power(model.law, true), feed_power(model.law, false)) {
    const double lead = model.cutter.lead_angle_deg * std::numbers::pi / 180.0;
    cos_lead_ = std::cos(lead);
    sin_lead_ = std::sin(lead);
    tan_lead_ = sin_lead_ / cos_lead_;  // lead < 90 degrees (validated)
    for (int i = 0; i < teeth_; ++i) {
      const double a = 2 * std::numbers::pi * i / teeth_;
      offset_cos_[static_cast<std::size_t>(i)] = std::cos(a);
      offset_sin_[static_cast<std::size_t>(i)] = std::sin(a);
    }
    if (has_runout_) {
      for (int i = 0; i < teeth_; ++i) {
        runout_mm_[static_cast<std::size_t>(i)] =
            1e-3 * model.cutter.radial_runout_um[static_cast<std::size_t>(i)];
      }
    }
  }

  bool runout() const noexcept { return has_runout_; }
  // Real-time: tooth i's radial runout from now on (a break moves its edge
  // back: runout_chip_mm then gives its chip, and its follower's, as for
  // runout).
  void set_runout_mm(int tooth, double mm) noexcept {
    if (tooth < 0 || tooth >= teeth_ || !std::isfinite(mm)) return;
    runout_mm_[static_cast<std::size_t>(tooth)] = mm;
    has_runout_ = true;
  }
  double runout_mm(int tooth) const noexcept {
    return tooth >= 0 && tooth < teeth_ ? runout_mm_[static_cast<std::size_t>(tooth)] : 0.0;
  }

  StructureModel& structure() noexcept { return structure_; }
  const StructureModel& structure() const noexcept { return structure_; }
  int sense() const noexcept { return sense_; }
  double radius_mm() const noexcept { return radius_mm_; }
  std::int64_t history_capacity() const noexcept { return capacity_; }

  // Precomputes the force-law coefficients for a cut (pow calls: once per
  // sample, not per step). Real-time safe.
  void set_operating_point(double spindle_rpm, double feed_per_tooth_mm, double depth_mm) noexcept {
    feed_mm_ = feed_per_tooth_mm;
    half_feed_mm_ = 0.5 * feed_per_tooth_mm;
    active_ = spindle_rpm > 0 && depth_mm > 0;
    const double v_m_min = cutting_speed_m_per_min(radius_mm_, spindle_rpm);
    double ct = 0, cn = 0;  // F_t = ct h^(1 + feed exponent), F_n likewise
    if (const auto* p = std::get_if<PowerLaw>(&law_)) {
      power_law_ = true;
      const double vs = v_m_min / 1000.0;
      if (active_) {
        ct = 1000.0 * p->cutting.coefficient_kn_per_mm2 *
             std::pow(depth_mm, 1.0 + p->cutting.depth_exponent) *
             std::pow(vs, p->cutting.speed_exponent);
        cn = 1000.0 * p->thrust.coefficient_kn_per_mm2 *
             std::pow(depth_mm, 1.0 + p->thrust.depth_exponent) *
             std::pow(vs, p->thrust.speed_exponent);
      }
      ca_ = 0;
    } else {
      const auto& l = std::get<LinearLaw>(law_);
      power_law_ = false;
      ct = l.k_t_n_per_mm2 * depth_mm;
      cn = l.k_n_n_per_mm2 * depth_mm;
      ca_ = force_scale_ * l.k_a_n_per_mm2 * depth_mm;
    }
    st_coef_ = force_scale_ * sense_d_ * ct;
    fr_coef_ = force_scale_ * cos_lead_ * cn;
  }

  // Real-time: every cutting pressure times `scale` from the next
  // set_operating_point on (a worn tool: scale > 1).
  void set_force_scale(double scale) noexcept {
    if (std::isfinite(scale) && scale > 0) force_scale_ = scale;
  }

  // Forces of the teeth for displacement change (dux, duy) since one delay
  // earlier; (c0, s0): tooth 0's direction (cos, sin of its angle), tooth i
  // being 2 pi i / teeth further on; tool_x_mm: cutter axis along the feed
  // (checked against the part's length unless check_length is false).
  //
  // half_sweep_rad: half the angle a tooth turns during the step. A tooth
  // whose tip crosses an edge of the part's width band during the step cuts
  // for the fraction of the step it is over the band (its y is taken as
  // linear in time over the step), so that the time in cut, and with it the
  // impulse of an interrupted cut, is exact to second order rather than
  // quantised to whole steps. 0: the indicator at the instant.
  StepForces tooth_forces(double c0, double s0, double tool_x_mm, bool check_length, double dux,
                          double duy, double half_sweep_rad = 0) const noexcept {
    StepForces f;
    if (!active_) return f;
    const double* __restrict oc = offset_cos_.data();
    const double* __restrict os = offset_sin_.data();
    const double r_sweep = radius_mm_ * half_sweep_rad;
    // A cutting tooth's tip is ahead of the axis by at most the radius: with
    // [axis, axis + radius] over the part no tooth needs the check.
    const bool whole_length =
        !check_length || (tool_x_mm >= 0 && tool_x_mm + radius_mm_ <= length_mm_);
    double tangential = 0;  // sum of sense x F_t
    for (int i = 0; i < teeth_; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const double c = c0 * oc[ii] - s0 * os[ii];
      if (c <= 0) continue;  // trailing half: that material is gone
      const double s = s0 * oc[ii] + c0 * os[ii];
      const double y = radius_mm_ * s;
      double weight = 1.0;
      const double dy = r_sweep * c;  // y's change over half the step
      if (y - dy < band_lo_mm_ || y + dy > band_hi_mm_) {
        if (dy > 0) {
          const double overlap = std::min(y + dy, band_hi_mm_) - std::max(y - dy, band_lo_mm_);
          if (overlap <= 0) continue;
          weight = std::min(1.0, overlap / (2 * dy));
        } else if (y < band_lo_mm_ || y > band_hi_mm_) {
          continue;
        }
      }
      if (!whole_length) {
        const double xt = tool_x_mm + radius_mm_ * c;
        if (xt < 0 || xt > length_mm_) continue;
      }
      const double nominal = feed_mm_ * c;
      const double chip =
          (has_runout_ ? runout_chip_mm(runout_mm_.data(), teeth_, i, feed_mm_, c) : nominal) +
          dux * c + duy * s;
      if (chip <= 0) {
        if (nominal >= half_feed_mm_ && feed_mm_ > 0) f.jumped_out = true;
        continue;
      }
      // st = sense F_t, fr = F_n cos(lead) (radial); the constants are
      // multiplied in while the chip is still being computed.
      double st, fr;
      if (power_law_) {
        const PowPair::Pair p = pow_(chip, PowPair::Pair{st_coef_ * weight, fr_coef_ * weight});
        st = p[0];
        fr = p[1];
        f.fz_n += fr * tan_lead_;
      } else {
        st = st_coef_ * weight * chip;
        fr = fr_coef_ * weight * chip;
        f.fz_n += fr * tan_lead_ + weight * ca_ * chip;
      }
      // F_x = -F_n cos(lead) cos(theta) + sense F_t sin(theta),
      // F_y = -F_n cos(lead) sin(theta) - sense F_t cos(theta), F_z = F_n sin(lead).
      f.fx_n += st * s - fr * c;
      f.fy_n -= fr * s + st * c;
      tangential += st;
      ++f.teeth_cutting;
    }
    f.tangential_sum_n = sense_d_ * tangential;
    return f;
  }

  // Relative displacement at fractional mid-step index `pos` (0 before the
  // history starts: the structure was at rest).
  void delayed(double pos, double& ux, double& uy) const noexcept {
    if (!(pos > -1.0)) {
      ux = uy = 0;
      return;
    }
    // floor() without a libm call: truncation is floor for pos >= 0.
    const std::int64_t i0 = pos >= 0 ? static_cast<std::int64_t>(pos) : -1;
    const double a = pos - static_cast<double>(i0);
    double x0 = 0, y0 = 0;
    if (i0 >= 0) {
      const auto j = static_cast<std::size_t>(i0 & mask_) * 2;
      x0 = history_[j];
      y0 = history_[j + 1];
    }
    const auto j1 = static_cast<std::size_t>((i0 + 1) & mask_) * 2;
    const double x1 = history_[j1];
    const double y1 = history_[j1 + 1];
    ux = x0 + a * (x1 - x0);
    uy = y0 + a * (y1 - y0);
  }

  // One internal step (see the top of this file). delay_steps: the delay in
  // internal steps (<= capacity - 2).
  // regenerative = false: the chip is the nominal one (the history is still
  // recorded), for running a cut onto its chatter-free periodic motion.
  // half_sweep_rad: see tooth_forces().
  StepForces step(double c0_mid, double s0_mid, double tool_x_mid_mm, bool check_length,
                  double delay_steps, double half_sweep_rad, bool regenerative = true) noexcept {
    double mx, my;
    structure_.predict_half_step(prev_fx_, prev_fy_, mx, my);
    double dx = mx, dy = my;
    if (regenerative) delayed(static_cast<double>(count_) - delay_steps, dx, dy);
    const auto slot = static_cast<std::size_t>(count_ & mask_) * 2;
    history_[slot] = mx;
    history_[slot + 1] = my;
    ++count_;
    const StepForces f =
        tooth_forces(c0_mid, s0_mid, tool_x_mid_mm, check_length, mx - dx, my - dy, half_sweep_rad);
    structure_.step(f.fx_n, f.fy_n);
    prev_fx_ = f.fx_n;
    prev_fy_ = f.fy_n;
    return f;
  }

  // Forces at the current instant (the end of the last step), for sampled
  // outputs: exact displacement now, delayed value interpolated
  // (regenerative = false: the nominal chip, as step()'s).
  StepForces forces_now(double c0, double s0, double tool_x_mm, bool check_length,
                        double delay_steps, bool regenerative = true) const noexcept {
    double ux, uy;
    structure_.relative(ux, uy);
    double dx = ux, dy = uy;
    if (regenerative) delayed(static_cast<double>(count_) - 0.5 - delay_steps, dx, dy);
    return tooth_forces(c0, s0, tool_x_mm, check_length, ux - dx, uy - dy);
  }

  // 1 + feed exponent of the cutting (or thrust) pressure: the power of the
  // chip in the force.
  static double feed_power(const CuttingLaw& law, bool cutting) noexcept {
    if (const auto* p = std::get_if<PowerLaw>(&law)) {
      return 1.0 + (cutting ? p->cutting.feed_exponent : p->thrust.feed_exponent);
    }
    return 1.0;
  }

  void set_previous_force(double fx_n, double fy_n) noexcept {
    prev_fx_ = fx_n;
    prev_fy_ = fy_n;
  }

  void clear_history() noexcept {
    for (auto& v : history_) v = 0;
    count_ = 0;
  }
  void reset() noexcept {
    structure_.reset();
    clear_history();
    prev_fx_ = prev_fy_ = 0;
  }

 private:
  StructureModel structure_;
  std::vector<double> history_;  // x, y pairs; a power-of-two ring
  std::int64_t capacity_;
  std::int64_t mask_;
  std::int64_t count_ = 0;
  double prev_fx_ = 0, prev_fy_ = 0;

  double radius_mm_, length_mm_, band_lo_mm_, band_hi_mm_;
  int teeth_;
  std::vector<double> offset_cos_, offset_sin_;  // tooth i's angle from tooth 0's
  std::vector<double> runout_mm_;                // tooth i's radial runout (mm)
  bool has_runout_ = false;
  double force_scale_ = 1.0;
  int sense_;
  double sense_d_;
  CuttingLaw law_;
  PowPair pow_;
  double cos_lead_ = 1, sin_lead_ = 0, tan_lead_ = 0;

  bool active_ = false;
  bool power_law_ = true;
  double feed_mm_ = 0, half_feed_mm_ = 0;
  double ca_ = 0;                     // linear law: F_a = ca h
  double st_coef_ = 0, fr_coef_ = 0;  // sense ct, cos(lead) cn
};

}  // namespace smc::machining::detail
