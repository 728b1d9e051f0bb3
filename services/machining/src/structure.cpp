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
  for (const DiscreteMode& m : modes_) {
    p11_.push_back(m.p11);
    p12_.push_back(m.p12);
    p21_.push_back(m.p21);
    p22_.push_back(m.p22);
    g1s_.push_back(m.sign * m.g1);
    g2s_.push_back(m.sign * m.g2);
    h11s_.push_back(m.sign * m.h11);
    h12s_.push_back(m.sign * m.h12);
    w_.push_back(m.sign);
    (m.axis == Axis::x ? half_gain_x_ : half_gain_y_) += m.hg1;
  }
  q_.assign(modes_.size(), 0.0);
  v_.assign(modes_.size(), 0.0);
}

Displacements StructureModel::displacements() const noexcept {
  Displacements d;
  for (std::size_t i = 0; i < modes_.size(); ++i) {
    const DiscreteMode& m = modes_[i];
    double& target = m.body == Body::tool ? (m.axis == Axis::x ? d.tool_x_mm : d.tool_y_mm)
                                          : (m.axis == Axis::x ? d.part_x_mm : d.part_y_mm);
    target += q_[i];
  }
  return d;
}

void StructureModel::relative(double& rel_x_mm, double& rel_y_mm) const noexcept {
  double rx = 0, ry = 0;
  for (std::size_t i = 0; i < nx_; ++i) rx += w_[i] * q_[i];
  for (std::size_t i = nx_; i < modes_.size(); ++i) ry += w_[i] * q_[i];
  rel_x_mm = rx;
  rel_y_mm = ry;
}

void StructureModel::reset() noexcept {
  for (std::size_t i = 0; i < modes_.size(); ++i) {
    q_[i] = 0;
    v_[i] = 0;
  }
}

void StructureModel::flush_tiny() noexcept {
  constexpr double kTiny = 1e-150;
  for (std::size_t i = 0; i < modes_.size(); ++i) {
    if (std::abs(q_[i]) < kTiny) q_[i] = 0;
    if (std::abs(v_[i]) < kTiny) v_[i] = 0;
  }
}

bool StructureModel::finite() const noexcept {
  // One test for all: a NaN or infinity anywhere makes the sum non-finite.
  double sum = 0;
  for (std::size_t i = 0; i < modes_.size(); ++i) sum += q_[i] + v_[i];
  return std::isfinite(sum);
}

}  // namespace smc::machining
