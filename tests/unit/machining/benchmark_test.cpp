// Published benchmark: the one-degree-of-freedom milling examples of
// Insperger & Stepan's semi-discretization papers.
//
// Source of the model and parameters:
//   T. Insperger, G. Stepan, "Updated semi-discretization method for periodic
//   delay-differential equations with discrete delay", Int. J. Numer. Meth.
//   Engng 61 (2004) 117-141, section 5 (milling), with the same model as
//   T. Insperger, G. Stepan, "Semi-discretization method for delayed
//   systems", Int. J. Numer. Meth. Engng 55 (2002) 503-518, and
//   T. Insperger, B.P. Mann, G. Stepan, P.V. Bayly, "Stability of up-milling
//   and down-milling, part 1: alternative analytical methods", Int. J.
//   Mach. Tools Manuf. 43 (2003) 25-34:
//     N = 2 straight teeth, K_t = 6e8 N/m^2, K_n = 2e8 N/m^2,
//     omega_n = 2 pi 922 rad/s, zeta = 0.011, m_t = 0.03993 kg, tool flexible
//     along the feed (x) only; slotting (a/D = 1) and down-milling with
//     a/D = 0.05; spindle speeds 5,000-25,000 rpm.
//
// What is compared, and why:
//   The published stability charts are figures, not tables: we cannot quote
//   their boundary depths to 1 % honestly. So the boundary our lobes give at
//   each test speed is checked against an independent computation written
//   here from the papers' equation of motion,
//     x'' + 2 zeta omega_n x' + omega_n^2 x
//        = -(w / m_t) h(t) (x(t) - x(t - tau)),
//     h(t) = sum_j g_j sin(phi_j) (K_t cos(phi_j) + K_n sin(phi_j)),
//   (phi_j the angle of tooth j from the y axis, g_j = 1 while it cuts):
//   direct fourth-order Runge-Kutta integration of this delay equation,
//   stepping exactly through the instants teeth enter and leave, with the
//   growth of a disturbance per tooth period measured over many periods. The
//   depths 2 % below and above our boundary must come out stable and
//   unstable. Independently of any discretization, two published features
//   are checked: (1) low-immersion down-milling loses stability by period
//   doubling (flip) near the speed where half the tooth-passing frequency
//   meets the natural frequency, f_tooth = 2 f_n / 3 (18,440 rpm here), and
//   is stable to large depths near f_tooth = f_n / 2 (13,830 rpm) (Insperger
//   et al. 2003, the charts of the 2004 paper; Davies et al., J. Manuf. Sci.
//   Eng. 124 (2002) 217-225); (2) for slotting, the lowest boundary is close to
//   the averaged (zeroth-order, Altintas & Budak, CIRP Annals 44 (1995) 357)
//   closed form a_lim = 2 k zeta (1 + zeta) / h_mean with h_mean = K_n / 2 for
//   two teeth in a slot, 0.298 mm.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "smc/machining/lobes.hpp"
#include "smc/machining/model_proto.hpp"
#include "test_models.hpp"

namespace mc = smc::machining;
using std::numbers::pi;

namespace {

constexpr double kKt = 6e8;  // N/m^2
constexpr double kKn = 2e8;
constexpr double kZeta = 0.011;
constexpr double kMass = 0.03993;  // kg
const double kOmega = 2 * pi * 922;

// The papers' 1-DOF milling equation, integrated directly (see the top).
class DirectIntegration {
 public:
  DirectIntegration(double radial_immersion, double rpm, double depth_m, int steps)
      : n_(steps),
        tau_(60.0 / (2 * rpm)),
        dt_(tau_ / steps),
        omega_rot_(2 * pi * rpm / 60),
        w_(depth_m) {
    if (radial_immersion >= 1) {
      phi_in_ = 0;
      phi_out_ = pi;
    } else {  // down-milling
      phi_in_ = std::acos(2 * radial_immersion - 1);
      phi_out_ = pi;
    }
    // Instants in [0, tau) where a tooth enters or leaves.
    for (int j = 0; j < 2; ++j) {
      for (const double phi : {phi_in_, phi_out_}) {
        double t = (phi - 2 * pi * j / 2) / omega_rot_;
        t = std::fmod(t, tau_);
        if (t < 0) t += tau_;
        switches_.push_back(t);
      }
    }
  }

  double h(double t) const {
    double sum = 0;
    for (int j = 0; j < 2; ++j) {
      double phi = std::fmod(omega_rot_ * t + pi * j, 2 * pi);
      if (phi < 0) phi += 2 * pi;
      if (phi >= phi_in_ && phi <= phi_out_) {
        sum += std::sin(phi) * (kKt * std::cos(phi) + kKn * std::sin(phi));
      }
    }
    return sum;
  }

  // ln of the growth of a disturbance per tooth period.
  double growth_per_period(int warmup, int measured) {
    // History on [-tau, 0]: a smooth, arbitrary disturbance.
    xs_.assign(static_cast<std::size_t>(n_ + 1), 0.0);
    vs_.assign(xs_.size(), 0.0);
    for (int i = 0; i <= n_; ++i) {
      const double t = -tau_ + i * dt_;
      xs_[static_cast<std::size_t>(i)] =
          1e-6 * (std::sin(3.1 * kOmega * t) + 0.3 * std::cos(kOmega * t));
      vs_[static_cast<std::size_t>(i)] =
          1e-6 * (3.1 * kOmega * std::cos(3.1 * kOmega * t) - 0.3 * kOmega * std::sin(kOmega * t));
    }
    double log_growth = 0;
    double previous = norm();
    for (int p = 0; p < warmup + measured; ++p) {
      period();
      const double now = norm();
      if (p >= warmup) log_growth += std::log(now / previous);
      // Renormalise so nothing overflows.
      for (std::size_t i = 0; i < xs_.size(); ++i) {
        xs_[i] /= now;
        vs_[i] /= now;
      }
      previous = 1;
    }
    return log_growth / measured;
  }

 private:
  // x at time t - tau + s (0 <= s <= tau): cubic Hermite on the stored period.
  double delayed(double s) const {
    double u = s / dt_;
    auto i = static_cast<int>(std::floor(u));
    if (i >= n_) i = n_ - 1;
    if (i < 0) i = 0;
    const double a = u - i;
    const auto k = static_cast<std::size_t>(i);
    const double x0 = xs_[k], x1 = xs_[k + 1], v0 = vs_[k] * dt_, v1 = vs_[k + 1] * dt_;
    const double a2 = a * a, a3 = a2 * a;
    return (2 * a3 - 3 * a2 + 1) * x0 + (a3 - 2 * a2 + a) * v0 + (-2 * a3 + 3 * a2) * x1 +
           (a3 - a2) * v1;
  }

  void rhs(double t, double s, double x, double v, double& dx, double& dv) const {
    dx = v;
    dv = -2 * kZeta * kOmega * v - kOmega * kOmega * x - w_ / kMass * h(t) * (x - delayed(s));
  }

  void rk4(double t, double s, double step, double& x, double& v) const {
    double k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
    rhs(t, s, x, v, k1x, k1v);
    rhs(t + step / 2, s + step / 2, x + step / 2 * k1x, v + step / 2 * k1v, k2x, k2v);
    rhs(t + step / 2, s + step / 2, x + step / 2 * k2x, v + step / 2 * k2v, k3x, k3v);
    rhs(t + step, s + step, x + step * k3x, v + step * k3v, k4x, k4v);
    x += step / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += step / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }

  // One tooth period: the new period's samples replace the stored ones.
  void period() {
    std::vector<double> nx, nv;
    nx.reserve(xs_.size());
    nv.reserve(vs_.size());
    double x = xs_.back(), v = vs_.back();
    nx.push_back(x);
    nv.push_back(v);
    for (int i = 0; i < n_; ++i) {
      double s = i * dt_;
      const double end = s + dt_;
      // Split the step at every entry or exit inside it.
      for (const double sw : switches_) {
        if (sw > s + 1e-15 && sw < end - 1e-15) {
          rk4(s, s, sw - s, x, v);
          s = sw;
        }
      }
      rk4(s, s, end - s, x, v);
      nx.push_back(x);
      nv.push_back(v);
    }
    xs_.swap(nx);
    vs_.swap(nv);
  }

  double norm() const {
    double s = 0;
    for (std::size_t i = 0; i < xs_.size(); ++i) {
      s += xs_[i] * xs_[i] + vs_[i] * vs_[i] / (kOmega * kOmega);
    }
    return std::sqrt(s);
  }

  int n_;
  double tau_, dt_, omega_rot_, w_;
  double phi_in_ = 0, phi_out_ = 0;
  std::vector<double> switches_;
  std::vector<double> xs_, vs_;
};

void expect_boundary_confirmed(double radial_immersion, double rpm) {
  const mc::MillingModel m = mc::test::insperger_1dof(radial_immersion);
  const mc::LobePoint p = mc::critical_depth_sdm(m, rpm, 0.05);
  ASSERT_NE(p.kind, mc::BoundaryKind::none) << rpm;
  const double below =
      DirectIntegration(radial_immersion, rpm, 0.98 * p.critical_depth_mm * 1e-3, 400)
          .growth_per_period(60, 120);
  const double above =
      DirectIntegration(radial_immersion, rpm, 1.02 * p.critical_depth_mm * 1e-3, 400)
          .growth_per_period(60, 120);
  EXPECT_LT(below, 0) << "a/D " << radial_immersion << ", " << rpm << " rpm: boundary "
                      << p.critical_depth_mm << " mm (" << mc::to_string(p.kind) << ")";
  EXPECT_GT(above, 0) << "a/D " << radial_immersion << ", " << rpm << " rpm: boundary "
                      << p.critical_depth_mm << " mm (" << mc::to_string(p.kind) << ")";
}

}  // namespace

TEST(InspergerStepan, DownMillingBoundaryConfirmedByDirectIntegration) {
  for (const double rpm : {6500.0, 10500.0, 18000.0, 22000.0}) expect_boundary_confirmed(0.05, rpm);
}

TEST(InspergerStepan, SlottingBoundaryConfirmedByDirectIntegration) {
  for (const double rpm : {7000.0, 12000.0, 16000.0, 21000.0}) expect_boundary_confirmed(1.0, rpm);
}

TEST(InspergerStepan, DownMillingHasPeriodDoublingLobes) {
  const mc::MillingModel m = mc::test::insperger_1dof(0.05);
  // f_tooth = 2 f_n / 3 (period doubling: chatter at f_tooth / 2 + f_tooth = f_n).
  const double flip_rpm = 60 * (2 * 922.0 / 3) / 2;  // 18,440 rpm
  const mc::LobePoint flip = mc::critical_depth_sdm(m, flip_rpm - 300, 0.05);
  EXPECT_EQ(flip.kind, mc::BoundaryKind::flip) << flip.critical_depth_mm;
  EXPECT_NEAR(flip.base_chatter_frequency_hz, (flip_rpm - 300) / 60.0, 1.0);  // half f_tooth
  // Near f_tooth = f_n / 2 the cut is stable far deeper than anywhere in the chart.
  mc::SdmOptions o;
  o.max_depth_mm = 10;
  const mc::LobePoint sweet = mc::critical_depth_sdm(m, 60 * 922.0 / 2 / 2, 0.05, o);
  EXPECT_GT(sweet.critical_depth_mm, 5 * flip.critical_depth_mm);
  // And a Hopf lobe at the high-speed end.
  EXPECT_EQ(mc::critical_depth_sdm(m, 22000, 0.05).kind, mc::BoundaryKind::hopf);
}

TEST(InspergerStepan, SlottingMinimumMatchesTheAveragedClosedForm) {
  const mc::MillingModel m = mc::test::insperger_1dof(1.0);
  const double k = kMass * kOmega * kOmega;                            // N/m
  const double a_avg = 2 * k * kZeta * (1 + kZeta) / (kKn / 2) * 1e3;  // mm: 0.298
  mc::LobeOptions o;
  o.rpm_min = 5000;
  o.rpm_max = 25000;
  o.speeds = 41;  // every 500 rpm: the lowest lobes are thousands of rpm wide
  o.feed_per_tooth_mm = 0.05;
  o.sdm.max_depth_mm = 10;
  double lowest = std::numeric_limits<double>::infinity();
  for (const mc::LobePoint& p : mc::stability_lobes(m, o))
    lowest = std::min(lowest, p.critical_depth_mm);
  EXPECT_NEAR(lowest, a_avg, 0.10 * a_avg) << "averaged closed form " << a_avg << " mm";
}

TEST(InspergerStepan, TheModelFilesAreTheTestedModels) {
  // cell/models holds both cases for `smc-cell lobes`; they must be the
  // models checked above.
  for (const double immersion : {0.05, 1.0}) {
    const std::string file = std::string(SMC_SOURCE_DIR) + "/cell/models/insperger_stepan_1dof_" +
                             (immersion < 1 ? "down_milling" : "slotting") + ".textproto";
    const mc::MillingModel f = mc::load_milling_model(file);
    const mc::MillingModel t = mc::test::insperger_1dof(immersion);
    EXPECT_EQ(f.cutter.teeth, t.cutter.teeth);
    EXPECT_NEAR(f.workpiece.width_mm / (2 * f.cutter.radius_mm), immersion, 1e-12);
    EXPECT_NEAR(f.workpiece.offset_mm / f.cutter.radius_mm,
                t.workpiece.offset_mm / t.cutter.radius_mm, 1e-12);
    EXPECT_EQ(f.workpiece.down_milling, t.workpiece.down_milling);
    ASSERT_TRUE(std::holds_alternative<mc::LinearLaw>(f.law));
    EXPECT_DOUBLE_EQ(std::get<mc::LinearLaw>(f.law).k_t_n_per_mm2, kKt * 1e-6);
    EXPECT_DOUBLE_EQ(std::get<mc::LinearLaw>(f.law).k_n_n_per_mm2, kKn * 1e-6);
    ASSERT_EQ(f.structure.tool_x.size(), 1u);
    EXPECT_NEAR(f.structure.tool_x[0].natural_frequency_rad_s, kOmega, 1e-9);
    EXPECT_DOUBLE_EQ(f.structure.tool_x[0].damping_ratio, kZeta);
    EXPECT_NEAR(f.structure.tool_x[0].stiffness_n_per_mm, kMass * kOmega * kOmega / 1000, 1e-9);
    EXPECT_EQ(mc::mode_count(f.structure), 1u);
  }
}
