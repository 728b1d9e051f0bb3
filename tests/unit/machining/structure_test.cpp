// Structural modes as exact discrete-time models: static deflection F/k,
// free response with the given natural frequency and damping, signs of tool
// and part.

#include "smc/machining/structure.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "smc/machining/paper_case.hpp"

namespace mc = smc::machining;
using std::numbers::pi;

namespace {

std::vector<mc::Mode> all_modes(const mc::MillingModel& m) {
  std::vector<mc::Mode> out;
  for (const auto* axis :
       {&m.structure.tool_x, &m.structure.tool_y, &m.structure.part_x, &m.structure.part_y}) {
    out.insert(out.end(), axis->begin(), axis->end());
  }
  return out;
}

struct Response {
  std::vector<double> t, q;
};

Response free_response(const mc::DiscreteMode& d, double h, int steps) {
  Response r;
  double q = 1.0, v = 0.0;
  for (int k = 0; k <= steps; ++k) {
    r.t.push_back(k * h);
    r.q.push_back(q);
    const double q1 = d.p11 * q + d.p12 * v;
    v = d.p21 * q + d.p22 * v;
    q = q1;
  }
  return r;
}

}  // namespace

TEST(Mode, StaticDeflectionIsForceOverStiffness) {
  for (const mc::Mode& mode : all_modes(mc::paper_case())) {
    const double h = 1e-5;
    const mc::DiscreteMode d = mc::discretise(mode, h);
    double q = 0, v = 0;
    const double f = 250.0;  // N
    // Ten time constants 1 / (zeta omega).
    const int steps =
        static_cast<int>(10 / (mode.damping_ratio * mode.natural_frequency_rad_s) / h);
    for (int k = 0; k < steps * 3; ++k) {
      const double q1 = d.p11 * q + d.p12 * v + d.g1 * f;
      v = d.p21 * q + d.p22 * v + d.g2 * f;
      q = q1;
    }
    EXPECT_NEAR(q, f / mode.stiffness_n_per_mm, 1e-9 * f / mode.stiffness_n_per_mm)
        << mode.natural_frequency_rad_s;
    EXPECT_NEAR(v, 0, 1e-9);
  }
}

TEST(Mode, FreeResponseHasTheNaturalFrequencyAndDamping) {
  for (const mc::Mode& mode : all_modes(mc::paper_case())) {
    const double w = mode.natural_frequency_rad_s;
    const double z = mode.damping_ratio;
    const double wd = w * std::sqrt(1 - z * z);
    const double h = 1e-5;
    const Response r =
        free_response(mc::discretise(mode, h), h, static_cast<int>(4 * 2 * pi / wd / h));
    // Upward zero crossings (linear interpolation) give the damped period.
    std::vector<double> crossings;
    for (std::size_t k = 1; k < r.q.size(); ++k) {
      if (r.q[k - 1] < 0 && r.q[k] >= 0) {
        crossings.push_back(r.t[k - 1] + h * r.q[k - 1] / (r.q[k - 1] - r.q[k]));
      }
    }
    ASSERT_GE(crossings.size(), 3u);
    const double period =
        (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
    const double omega_n = 2 * pi / period / std::sqrt(1 - z * z);
    EXPECT_NEAR(omega_n, w, 1e-5 * w);
    // The exact solution at every step: the discretisation is exact.
    const double a = z * w;
    double worst = 0;
    for (std::size_t k = 0; k < r.q.size(); ++k) {
      const double t = r.t[k];
      const double exact = std::exp(-a * t) * (std::cos(wd * t) + a / wd * std::sin(wd * t));
      worst = std::max(worst, std::abs(r.q[k] - exact));
    }
    EXPECT_LT(worst, 1e-9);  // rounding only, over thousands of steps
  }
}

TEST(Mode, LogarithmicDecrementOfTheSimulatedPeaksGivesTheDamping) {
  for (const mc::Mode& mode : all_modes(mc::paper_case())) {
    const double h = 1e-6;
    const double wd = mode.natural_frequency_rad_s * std::sqrt(1 - std::pow(mode.damping_ratio, 2));
    const Response r =
        free_response(mc::discretise(mode, h), h, static_cast<int>(3 * 2 * pi / wd / h));
    std::vector<double> peaks;
    for (std::size_t k = 1; k + 1 < r.q.size(); ++k) {
      if (r.q[k] > r.q[k - 1] && r.q[k] >= r.q[k + 1]) peaks.push_back(r.q[k]);
    }
    ASSERT_GE(peaks.size(), 2u);
    const double delta = std::log(peaks[0] / peaks[1]);
    EXPECT_NEAR(delta / std::sqrt(4 * pi * pi + delta * delta), mode.damping_ratio, 2e-4)
        << mode.natural_frequency_rad_s;
  }
}

TEST(StructureModel, ToolTakesTheForcePartItsReaction) {
  mc::Structure s;
  s.tool_x = {mc::Mode{4500, 0.07, 14000}};
  s.part_x = {mc::Mode{2600, 0.09, 9500}};
  s.tool_y = {mc::Mode{4100, 0.11, 14000}, mc::Mode{20000, 0.05, 50000}};
  mc::StructureModel model(s, 1e-5);
  ASSERT_EQ(model.size(), 4u);
  // x modes first.
  EXPECT_EQ(model.mode(0).axis, mc::Axis::x);
  EXPECT_EQ(model.mode(1).body, mc::Body::part);
  EXPECT_EQ(model.mode(1).sign, -1);
  for (int k = 0; k < 100000; ++k) model.step(100.0, -50.0);
  const mc::Displacements d = model.displacements();
  EXPECT_NEAR(d.tool_x_mm, 100.0 / 14000, 1e-10);
  EXPECT_NEAR(d.part_x_mm, -100.0 / 9500, 1e-10);
  EXPECT_NEAR(d.tool_y_mm, -50.0 / 14000 - 50.0 / 50000, 1e-10);
  EXPECT_NEAR(d.part_y_mm, 0, 1e-15);
  EXPECT_NEAR(d.rel_x_mm(), 100.0 / 14000 + 100.0 / 9500, 1e-10);
  double rx, ry;
  model.relative(rx, ry);
  EXPECT_DOUBLE_EQ(rx, d.rel_x_mm());
  EXPECT_DOUBLE_EQ(ry, d.rel_y_mm());
  // The half-step prediction at rest with the same force stays put.
  double px, py;
  model.predict_half_step(100.0, -50.0, px, py);
  EXPECT_NEAR(px, rx, 1e-12);
  EXPECT_NEAR(py, ry, 1e-12);
  model.reset();
  EXPECT_EQ(model.displacements().tool_x_mm, 0);
  EXPECT_TRUE(model.finite());
}

TEST(StructureModel, RejectsBadSteps) {
  EXPECT_THROW(mc::discretise(mc::Mode{100, 0.1, 1}, 0), std::invalid_argument);
  EXPECT_THROW(mc::discretise(mc::Mode{100, 1.5, 1}, 1e-5), std::invalid_argument);
}
