#include "smc/machining/structure.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

namespace smc::machining {

namespace {

// exp([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, 1]]: the exact zero-order-hold
// discretisation of q'' + 2 zeta w q' + w^2 q = (w^2 / k) f.
Eigen::Matrix3d zoh(const Mode& m, double h) {
  const double w = m.natural_frequency_rad_s;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  a(0, 1) = 1.0;
  a(1, 0) = -w * w;
  a(1, 1) = -2.0 * m.damping_ratio * w;
  a(1, 2) = w * w / m.stiffness_n_per_mm;
  return (a * h).exp();
}

}  // namespace

DiscreteMode discretise(const Mode& mode, double step_s, Body body, Axis axis) {
  if (!(std::isfinite(step_s) && step_s > 0)) {
    throw std::invalid_argument("discretise: step must be > 0");
  }
  if (!(mode.natural_frequency_rad_s > 0 && mode.damping_ratio > 0 && mode.damping_ratio < 1 &&
        mode.stiffness_n_per_mm > 0)) {
    throw std::invalid_argument("discretise: invalid mode");
  }
  DiscreteMode d;
  d.body = body;
  d.axis = axis;
  d.natural_frequency_rad_s = mode.natural_frequency_rad_s;
  d.sign = body == Body::tool ? 1.0 : -1.0;
  const Eigen::Matrix3d full = zoh(mode, step_s);
  d.p11 = full(0, 0);
  d.p12 = full(0, 1);
  d.p21 = full(1, 0);
  d.p22 = full(1, 1);
  d.g1 = full(0, 2);
  d.g2 = full(1, 2);
  const Eigen::Matrix3d half = zoh(mode, step_s / 2);
  d.h11 = half(0, 0);
  d.h12 = half(0, 1);
  d.hg1 = half(0, 2);
  return d;
}

StructureModel::StructureModel(const Structure& structure, double step_s) : step_s_(step_s) {
  const auto add = [&](const std::vector<Mode>& modes, Body body, Axis axis) {
    for (const Mode& m : modes) modes_.push_back(discretise(m, step_s, body, axis));
  };
  // x modes first, then y modes: the stepping loops sum each axis separately.
  add(structure.tool_x, Body::tool, Axis::x);
  add(structure.part_x, Body::part, Axis::x);
  nx_ = modes_.size();
  add(structure.tool_y, Body::tool, Axis::y);
  add(structure.part_y, Body::part, Axis::y);
  for (std::size_t i = 0; i < modes_.size(); ++i) {
    const DiscreteMode& m = modes_[i];
    const double g1s = m.sign * m.g1, g2s = m.sign * m.g2;
    const double h11s = m.sign * m.h11, h12s = m.sign * m.h12;
    Coefficients c{};
    c.col_q = Pair{m.p11, m.p21};
    c.col_v = Pair{m.p12, m.p22};
    c.col_f = Pair{g1s, g2s};
    c.pred = Pair{h11s * m.p11 + h12s * m.p21, h11s * m.p12 + h12s * m.p22};
    c.half = Pair{h11s, h12s};
    coef_.push_back(c);
    slot_.push_back(
        static_cast<std::uint8_t>((m.body == Body::tool ? 0 : 2) + (m.axis == Axis::x ? 0 : 1)));
    const bool x = i < nx_;
    (x ? half_gain_x_ : half_gain_y_) += m.hg1;
    (x ? mid_gain_x_ : mid_gain_y_) += h11s * g1s + h12s * g2s;
  }
  mid_gain_x_ += half_gain_x_;
  mid_gain_y_ += half_gain_y_;
  z_.assign(modes_.size(), Pair{0, 0});
}

void StructureModel::predict_from_state(double fx_tool_n, double fy_tool_n, double& rel_x_mm,
                                        double& rel_y_mm) const noexcept {
  rel_x_mm = half_gain_x_ * fx_tool_n;
  rel_y_mm = half_gain_y_ * fy_tool_n;
  add_by_axis(rel_x_mm, rel_y_mm, [this](std::size_t i) {
    const Pair p = coef_[i].half * z_[i];
    return p[0] + p[1];
  });
}

Displacements StructureModel::displacements() const noexcept {
  double sum[4] = {0, 0, 0, 0};  // tool x, tool y, part x, part y
  const std::uint8_t* slot = slot_.data();
  for (std::size_t i = 0; i < z_.size(); ++i) sum[slot[i]] += z_[i][0];
  Displacements d;
  d.tool_x_mm = sum[0];
  d.tool_y_mm = sum[1];
  d.part_x_mm = sum[2];
  d.part_y_mm = sum[3];
  return d;
}

void StructureModel::relative(double& rel_x_mm, double& rel_y_mm) const noexcept {
  rel_x_mm = rel_y_mm = 0;
  add_by_axis(rel_x_mm, rel_y_mm, [this](std::size_t i) { return modes_[i].sign * z_[i][0]; });
}

void StructureModel::reset() noexcept {
  for (Pair& x : z_) x = Pair{0, 0};
  mid_valid_ = false;
}

void StructureModel::flush_tiny() noexcept {
  constexpr double kTiny = 1e-150;
  for (Pair& p : z_) {
    for (int j = 0; j < 2; ++j) {
      if (p[j] != 0 && std::abs(p[j]) < kTiny) {
        p[j] = 0;
        mid_valid_ = false;
      }
    }
  }
}

bool StructureModel::finite() const noexcept {
  // One test for all: a NaN or infinity anywhere makes the sum non-finite.
  Pair sum{0, 0};
  for (const Pair& p : z_) sum += p;
  return std::isfinite(sum[0] + sum[1]);
}

}  // namespace smc::machining
