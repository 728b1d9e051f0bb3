#pragma once
// The structure as exact discrete-time state-space models: each mode
// q'' + 2 zeta omega q' + omega^2 q = (omega^2 / k) F is discretised for a fixed
// step h with a zero-order hold on the force, [q v]_{k+1} = Phi [q v]_k + Gamma F_k,
// Phi = exp(A h), Gamma = A^-1 (Phi - I) B (computed with a matrix exponential).
// The half-step pair (Phi_h, Gamma_h) is kept too: the simulator predicts the
// displacement at the middle of a step with it.
//
// The tool's modes are driven by the cutting force on the tool, the part's by
// its reaction (sign -1). Displacements in mm, velocities in mm/s.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "smc/machining/model.hpp"

namespace smc::machining {

enum class Body : std::uint8_t { tool, part };
enum class Axis : std::uint8_t { x, y };

struct DiscreteMode {
  Body body = Body::tool;
  Axis axis = Axis::x;
  double sign = 1;  // +1 tool (driven by F), -1 part (driven by -F)
  double natural_frequency_rad_s = 0;
  // Full step: q' = p11 q + p12 v + g1 f, v' = p21 q + p22 v + g2 f (f = sign * F_axis).
  double p11 = 1, p12 = 0, p21 = 0, p22 = 1, g1 = 0, g2 = 0;
  // Half step, displacement row only: q(h/2) = h11 q + h12 v + hg1 f.
  double h11 = 1, h12 = 0, hg1 = 0;
};

// Exact discretisation of one mode for step h (s). Throws std::invalid_argument
// for a non-positive step or an invalid mode.
DiscreteMode discretise(const Mode& mode, double step_s, Body body = Body::tool,
                        Axis axis = Axis::x);

// Displacements of tool and part (mm) and the relative displacement
// tool - part, which is what changes the chip.
struct Displacements {
  double tool_x_mm = 0, tool_y_mm = 0;
  double part_x_mm = 0, part_y_mm = 0;
  double rel_x_mm() const noexcept { return tool_x_mm - part_x_mm; }
  double rel_y_mm() const noexcept { return tool_y_mm - part_y_mm; }
};

// All modes of a structure, stepped together. Construction allocates; the
// step functions are real-time safe (no allocation, no lock, no throw).
// Modes are numbered tool_x, part_x, tool_y, part_y (each in document order):
// all x modes before the y modes.
class StructureModel {
 public:
  StructureModel(const Structure& structure, double step_s);

  double step_s() const noexcept { return step_s_; }
  std::size_t size() const noexcept { return modes_.size(); }
  const DiscreteMode& mode(std::size_t i) const noexcept { return modes_[i]; }

  // Advances one step with the force on the tool held constant (N). The
  // displacement half a step into the next step, with the force still held
  // (what predict_half_step() returns for the same force), is computed on the
  // way from the state before this step: mid = (H Phi) z + (H Gamma + Gamma_h) F.
  // The simulator's step waits for that value, and in this form it waits for
  // the force through one multiply-add instead of through the whole update.
  void step(double fx_tool_n, double fy_tool_n) noexcept {
    // Local restrict pointers: the stores to the state cannot then make the
    // compiler reload the coefficients' addresses in every iteration.
    const Coefficients* __restrict c = coef_.data();
    Pair* __restrict z = z_.data();
    const std::size_t nx = nx_;
    const std::size_t n = coef_.size();
    Pair bx2{0, 0}, by2{0, 0};
    for (std::size_t i = 0; i < nx; ++i) advance(c[i], z[i], fx_tool_n, bx2);
    for (std::size_t i = nx; i < n; ++i) advance(c[i], z[i], fy_tool_n, by2);
    const double bx = bx2[0] + bx2[1];
    const double by = by2[0] + by2[1];
    mid_x_ = bx + mid_gain_x_ * fx_tool_n;
    mid_y_ = by + mid_gain_y_ * fy_tool_n;
    mid_fx_ = fx_tool_n;
    mid_fy_ = fy_tool_n;
    mid_valid_ = true;
  }
  // Relative displacement tool - part (mm) half a step ahead, with the force
  // (on the tool) held at the given value. After step() with the same force
  // this is the value step() computed (bit for bit the same every time the
  // same calls are made); otherwise it is computed from the state.
  void predict_half_step(double fx_tool_n, double fy_tool_n, double& rel_x_mm,
                         double& rel_y_mm) const noexcept {
    if (mid_valid_ && fx_tool_n == mid_fx_ && fy_tool_n == mid_fy_) {
      rel_x_mm = mid_x_;
      rel_y_mm = mid_y_;
      return;
    }
    predict_from_state(fx_tool_n, fy_tool_n, rel_x_mm, rel_y_mm);
  }
  Displacements displacements() const noexcept;
  // Relative displacement tool - part now (mm).
  void relative(double& rel_x_mm, double& rel_y_mm) const noexcept;

  // Modal state access (mm, mm/s), for tests and for the stability criterion.
  double q(std::size_t i) const noexcept { return z_[i][0]; }
  double v(std::size_t i) const noexcept { return z_[i][1]; }
  void set_state(std::size_t i, double q_mm, double v_mm_s) noexcept {
    z_[i] = Pair{q_mm, v_mm_s};
    mid_valid_ = false;
  }
  void reset() noexcept;
  bool finite() const noexcept;
  // Sets displacements and velocities below 1e-150 (mm, mm/s) to exactly 0,
  // so that a ringing-down structure never computes with subnormal numbers
  // (which are two orders of magnitude slower). Call now and then (the
  // simulator does once per sample).
  void flush_tiny() noexcept;

 private:
  // Two doubles in one SSE register (GCC/Clang vector extension): a mode's
  // (q, v), or one column of its update. The mode update is then three
  // packed products instead of six scalar ones.
  using Pair = double __attribute__((vector_size(16)));

  // One mode's coefficients as columns, with the mode's sign folded in
  // (the part is driven by -F, and its displacement counts negatively in
  // tool - part): (q, v)' = q col_q + v col_v + F col_f with
  // col_q = (p11, p21), col_v = (p12, p22), col_f = sign (g1, g2); the
  // next half-step prediction's row folded into the step,
  // pred = sign (h11, h12) . (q, v)' = (ma, mb) . (q, v) + (force term); and
  // the half-step row itself, half = sign (h11, h12).
  struct Coefficients {
    Pair col_q, col_v, col_f, pred, half;
  };
  // One mode one step; adds its share of the next half-step prediction to b
  // (as a pair, summed by the caller).
  static void advance(const Coefficients& c, Pair& z, double f, Pair& b) noexcept;
  void predict_from_state(double fx_tool_n, double fy_tool_n, double& rel_x_mm,
                          double& rel_y_mm) const noexcept;
  // Adds term(i) of every x mode to x and of every y mode to y.
  template <class Term>
  void add_by_axis(double& x, double& y, Term term) const noexcept {
    for (std::size_t i = 0; i < nx_; ++i) x += term(i);
    for (std::size_t i = nx_; i < modes_.size(); ++i) y += term(i);
  }

  double step_s_;
  std::vector<DiscreteMode> modes_;
  std::size_t nx_ = 0;  // modes_[0, nx_) are along x
  std::vector<Coefficients> coef_;
  std::vector<std::uint8_t> slot_;  // per mode: 0 tool x, 1 tool y, 2 part x, 3 part y
  // Per axis: the half-step force gain sign^2 hg1 = hg1 summed, and the
  // prediction's force gain sum(h11s g1s + h12s g2s) + half_gain.
  double half_gain_x_ = 0, half_gain_y_ = 0;
  double mid_gain_x_ = 0, mid_gain_y_ = 0;
  // The prediction made by the last step() and the force it holds.
  double mid_x_ = 0, mid_y_ = 0, mid_fx_ = 0, mid_fy_ = 0;
  bool mid_valid_ = false;
  std::vector<Pair> z_;  // (q, v) per mode
};

inline void StructureModel::advance(const Coefficients& c, Pair& z, double f, Pair& b) noexcept {
  const Pair zz = z;
  b += c.pred * zz;
  z = c.col_q * zz[0] + c.col_v * zz[1] + c.col_f * f;
}

}  // namespace smc::machining
