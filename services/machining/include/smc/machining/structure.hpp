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

  // Advances one step with the force on the tool held constant (N).
  void step(double fx_tool_n, double fy_tool_n) noexcept {
    const std::size_t n = modes_.size();
    for (std::size_t i = 0; i < n; ++i) {
      const double f = i < nx_ ? fx_tool_n : fy_tool_n;
      const double q = q_[i];
      const double v = v_[i];
      q_[i] = p11_[i] * q + p12_[i] * v + g1s_[i] * f;
      v_[i] = p21_[i] * q + p22_[i] * v + g2s_[i] * f;
    }
  }
  // Relative displacement tool - part (mm) half a step ahead, with the force
  // (on the tool) held at the given value.
  void predict_half_step(double fx_tool_n, double fy_tool_n, double& rel_x_mm,
                         double& rel_y_mm) const noexcept {
    double rx = half_gain_x_ * fx_tool_n, ry = half_gain_y_ * fy_tool_n;
    const std::size_t n = modes_.size();
    for (std::size_t i = 0; i < nx_; ++i) rx += h11s_[i] * q_[i] + h12s_[i] * v_[i];
    for (std::size_t i = nx_; i < n; ++i) ry += h11s_[i] * q_[i] + h12s_[i] * v_[i];
    rel_x_mm = rx;
    rel_y_mm = ry;
  }
  Displacements displacements() const noexcept;
  // Relative displacement tool - part now (mm).
  void relative(double& rel_x_mm, double& rel_y_mm) const noexcept;

  // Modal state access (mm, mm/s), for tests and for the stability criterion.
  double q(std::size_t i) const noexcept { return q_[i]; }
  double v(std::size_t i) const noexcept { return v_[i]; }
  void set_state(std::size_t i, double q_mm, double v_mm_s) noexcept {
    q_[i] = q_mm;
    v_[i] = v_mm_s;
  }
  void reset() noexcept;
  bool finite() const noexcept;
  // Sets displacements and velocities below 1e-150 (mm, mm/s) to exactly 0,
  // so that a ringing-down structure never computes with subnormal numbers
  // (which are two orders of magnitude slower). Call now and then (the
  // simulator does once per sample).
  void flush_tiny() noexcept;

 private:
  double step_s_;
  std::vector<DiscreteMode> modes_;
  std::size_t nx_ = 0;  // modes_[0, nx_) are along x
  // The same coefficients as arrays for the stepping loops, with the mode's
  // sign folded in: g1s = sign g1 (the part is driven by -F), h11s = sign h11
  // (the part's displacement counts negatively in tool - part); the half-step
  // force gains sign^2 hg1 = hg1 summed per axis.
  std::vector<double> p11_, p12_, p21_, p22_, g1s_, g2s_, h11s_, h12s_, w_;
  double half_gain_x_ = 0, half_gain_y_ = 0;
  std::vector<double> q_;
  std::vector<double> v_;
};

}  // namespace smc::machining
