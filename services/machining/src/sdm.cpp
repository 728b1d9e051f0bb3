#include "sdm.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

namespace smc::machining::detail {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kPi = std::numbers::pi;

// Deterministic start vector for the Arnoldi iteration.
void fill_start(VectorXd& v) {
  std::uint64_t x = 0x9E3779B97F4A7C15ull;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    v(i) = static_cast<double>(x >> 11) * (1.0 / 9007199254740992.0) - 0.5;
  }
  v.normalize();
}

}  // namespace

BoundaryKind classify(std::complex<double> mu) noexcept {
  const double arg = std::abs(std::arg(mu));
  if (arg < 1e-3) return BoundaryKind::fold;
  if (kPi - arg < 1e-3) return BoundaryKind::flip;
  return BoundaryKind::hopf;
}

struct SdmSystem::Impl {
  int n = 0;    // states
  int m = 0;    // intervals per period
  int lag = 0;  // delay in intervals
  double dt = 0;
  MatrixXd a, b0, c;  // n x n, n x 2, 2 x n
  // Per interval: P (n x n, column-major), R0 and R1 (n x 2, row-major).
  std::vector<double> p, r0, r1;
  std::vector<double> ubuf;  // u_j, j in [-lag, m], 2 per entry
  VectorXd xi, xi_next;

  int dim() const { return n + 2 * lag; }

  // P_i, R0_i, R1_i for every interval. Mat: the matrix type (a small
  // fixed-capacity one avoids the heap for up to 8 modes).
  template <typename Mat, typename MatN2>
  void build_with(const std::vector<Mat2>& h_bar) {
    const auto nn = static_cast<std::size_t>(n);
    const Mat a_s = a;
    const MatN2 b_s = b0;
    const Eigen::Matrix<double, 2, Eigen::Dynamic, 0, 2, Mat::MaxColsAtCompileTime> c_s = c;
    const Mat identity = Mat::Identity(n, n);
    Mat pm(n, n), g0(n, n), g1(n, n);
    MatN2 r0m(n, 2), r1m(n, 2);
    for (int i = 0; i < m; ++i) {
      const Mat2& h = h_bar[static_cast<std::size_t>(i)];
      const bool same = i > 0 && h == h_bar[static_cast<std::size_t>(i - 1)];
      if (!same) {
        Eigen::Matrix2d hm;
        hm << h[0], h[1], h[2], h[3];
        const MatN2 bi = b_s * hm;  // n x 2
        const Mat ai = a_s - bi * c_s;
        pm = (ai * dt).exp();
        const Eigen::PartialPivLU<Mat> lu(ai);
        const auto pivots = lu.matrixLU().diagonal().cwiseAbs();
        if (pivots.minCoeff() > 1e-12 * pivots.maxCoeff()) {
          g0 = lu.solve(pm - identity);
          g1 = g0 - lu.solve(pm - g0 / dt);
        } else {
          // Near-singular A_i: the integrals from an augmented exponential.
          MatrixXd big = MatrixXd::Zero(3 * n, 3 * n);
          big.topLeftCorner(n, n) = ai;
          big.block(0, n, n, n) = MatrixXd::Identity(n, n);
          big.block(n, 2 * n, n, n) = MatrixXd::Identity(n, n) / dt;
          const MatrixXd e = (big * dt).exp();
          g0 = e.block(0, n, n, n);
          g1 = e.block(0, 2 * n, n, n);
        }
        r0m = (g0 - g1) * bi;
        r1m = g1 * bi;
      }
      const std::size_t base_p = static_cast<std::size_t>(i) * nn * nn;
      const std::size_t base_r = static_cast<std::size_t>(i) * nn * 2;
      for (int row = 0; row < n; ++row) {
        for (int col = 0; col < n; ++col) {
          p[base_p + static_cast<std::size_t>(col) * nn + static_cast<std::size_t>(row)] =
              pm(row, col);
        }
        for (int col = 0; col < 2; ++col) {
          r0[base_r + static_cast<std::size_t>(row) * 2 + static_cast<std::size_t>(col)] =
              r0m(row, col);
          r1[base_r + static_cast<std::size_t>(row) * 2 + static_cast<std::size_t>(col)] =
              r1m(row, col);
        }
      }
    }
  }

  void build(const std::vector<Mat2>& h_bar) {
    if (static_cast<int>(h_bar.size()) != m) {
      throw std::invalid_argument("semi-discretization: wrong number of interval matrices");
    }
    if (n <= 16) {
      using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 16, 16>;
      using SmallN2 = Eigen::Matrix<double, Eigen::Dynamic, 2, 0, 16, 2>;
      build_with<Small, SmallN2>(h_bar);
    } else {
      build_with<MatrixXd, Eigen::Matrix<double, Eigen::Dynamic, 2>>(h_bar);
    }
  }

  double* u(int j) { return &ubuf[static_cast<std::size_t>(j + lag) * 2]; }

  void output_u(const VectorXd& x, double* out) const {
    out[0] = 0;
    out[1] = 0;
    for (int k = 0; k < n; ++k) {
      out[0] += c(0, k) * x(k);
      out[1] += c(1, k) * x(k);
    }
  }

  // z_out = monodromy z_in (one period of the semi-discretised map).
  void apply(const double* z_in, double* z_out) {
    const auto nn = static_cast<std::size_t>(n);
    for (int k = 0; k < n; ++k) xi(k) = z_in[k];
    for (int l = 1; l <= lag; ++l) {
      double* d = u(-l);
      d[0] = z_in[n + 2 * (l - 1)];
      d[1] = z_in[n + 2 * (l - 1) + 1];
    }
    output_u(xi, u(0));
    for (int i = 0; i < m; ++i) {
      const double* pa = &p[static_cast<std::size_t>(i) * nn * nn];
      const double* ra = &r0[static_cast<std::size_t>(i) * nn * 2];
      const double* rb = &r1[static_cast<std::size_t>(i) * nn * 2];
      const double* ua = u(i - lag);
      const double* ub = u(i - lag + 1);
      // xi_next = P xi + R0 u_a + R1 u_b, column by column (no reduction chain).
      for (int row = 0; row < n; ++row) {
        const std::size_t rr = static_cast<std::size_t>(row) * 2;
        xi_next(row) = ra[rr] * ua[0] + ra[rr + 1] * ua[1] + rb[rr] * ub[0] + rb[rr + 1] * ub[1];
      }
      for (int col = 0; col < n; ++col) {
        const double* pcol = pa + static_cast<std::size_t>(col) * nn;
        const double x = xi(col);
        for (int row = 0; row < n; ++row) xi_next(row) += pcol[row] * x;
      }
      xi.swap(xi_next);
      output_u(xi, u(i + 1));
    }
    for (int k = 0; k < n; ++k) z_out[k] = xi(k);
    for (int l = 1; l <= lag; ++l) {
      const double* s = u(m - l);
      z_out[n + 2 * (l - 1)] = s[0];
      z_out[n + 2 * (l - 1) + 1] = s[1];
    }
  }

  Multiplier from_value(std::complex<double> mu) const {
    Multiplier r;
    r.value = mu;
    r.magnitude = std::abs(mu);
    r.kind = classify(mu);
    return r;
  }

  Multiplier dense() {
    const int d = dim();
    MatrixXd phi(d, d);
    VectorXd e = VectorXd::Zero(d), col(d);
    for (int j = 0; j < d; ++j) {
      e.setZero();
      e(j) = 1;
      apply(e.data(), col.data());
      phi.col(j) = col;
    }
    Eigen::EigenSolver<MatrixXd> es(phi, false);
    const auto ev = es.eigenvalues();
    Eigen::Index best = 0;
    for (Eigen::Index i = 1; i < ev.size(); ++i) {
      if (std::abs(ev(i)) > std::abs(ev(best))) best = i;
    }
    return from_value(ev(best));
  }

  // Arnoldi with explicit restarts; dense fallback if it does not converge.
  Multiplier arnoldi() {
    const int d = dim();
    const int k_max = std::min(d, 80);
    MatrixXd v(d, k_max + 1);
    MatrixXd hs = MatrixXd::Zero(k_max + 1, k_max);
    VectorXd start(d), w(d);
    fill_start(start);
    constexpr double kTol = 1e-9;
    for (int restart = 0; restart < 4; ++restart) {
      v.col(0) = start;
      hs.setZero();
      int next_check = std::min(24, k_max);
      for (int j = 0; j < k_max; ++j) {
        apply(v.col(j).data(), w.data());
        // Modified Gram-Schmidt, twice for orthogonality.
        for (int pass = 0; pass < 2; ++pass) {
          for (int i = 0; i <= j; ++i) {
            const double hij = v.col(i).dot(w);
            hs(i, j) += hij;
            w -= hij * v.col(i);
          }
        }
        const double beta = w.norm();
        hs(j + 1, j) = beta;
        const int k = j + 1;
        const bool breakdown = beta <= 1e-13 * std::max(1.0, hs.topLeftCorner(k, k).norm());
        if (!breakdown) v.col(j + 1) = w / beta;
        if (k == next_check || k == k_max || breakdown) {
          next_check = std::min(k_max, k + std::max(8, k / 2));
          const MatrixXd hk = hs.topLeftCorner(k, k);
          const Eigen::EigenSolver<MatrixXd> es(hk, false);
          const auto ev = es.eigenvalues();
          Eigen::Index best = 0;
          for (Eigen::Index i = 1; i < ev.size(); ++i) {
            if (std::abs(ev(i)) > std::abs(ev(best))) best = i;
          }
          const std::complex<double> mu = ev(best);
          // Ritz vector y of mu by one step of inverse iteration; the
          // residual of the Ritz pair is beta |y_k| / |y|.
          Eigen::MatrixXcd shifted = hk.cast<std::complex<double>>();
          const std::complex<double> shift =
              mu + std::complex<double>(1e-10 * std::max(std::abs(mu), 1e-3), 0);
          for (int i = 0; i < k; ++i) shifted(i, i) -= shift;
          const Eigen::VectorXcd y = shifted.partialPivLu().solve(Eigen::VectorXcd::Ones(k).eval());
          const double ynorm = y.norm();
          const double residual = breakdown ? 0.0 : beta * std::abs(y(k - 1)) / ynorm;
          if (breakdown || k == d || residual <= kTol * std::max(std::abs(mu), 1e-3)) {
            return from_value(mu);
          }
          if (k == k_max) {
            // Restart from the dominant Ritz vector (real and imaginary parts).
            start = v.leftCols(k) * (y.real() + y.imag()) / ynorm;
            if (start.norm() == 0) fill_start(start);
            start.normalize();
          }
        }
        if (breakdown) break;
      }
    }
    return dense();
  }
};

SdmSystem::SdmSystem(const Structure& structure, double period_s, int delay_periods, int intervals)
    : impl_(std::make_unique<Impl>()) {
  if (!(period_s > 0) || delay_periods < 1 || intervals < 1) {
    throw std::invalid_argument("semi-discretization: bad period, delay or interval count");
  }
  Impl& s = *impl_;
  const auto modes = static_cast<int>(mode_count(structure));
  if (modes == 0) throw std::invalid_argument("semi-discretization: no modes");
  s.n = 2 * modes;
  s.m = intervals;
  s.lag = intervals * delay_periods;
  s.dt = period_s / intervals;
  s.a = MatrixXd::Zero(s.n, s.n);
  s.b0 = MatrixXd::Zero(s.n, 2);
  s.c = MatrixXd::Zero(2, s.n);
  int j = 0;
  // Mode j's state is (q, q' / omega): the same multipliers as (q, q'), with
  // entries of the order of omega rather than omega^2, which keeps the matrix
  // exponentials cheap and well conditioned.
  const auto add = [&](const std::vector<Mode>& list, double sign, int axis) {
    for (const Mode& md : list) {
      const double w = md.natural_frequency_rad_s;
      s.a(2 * j, 2 * j + 1) = w;
      s.a(2 * j + 1, 2 * j) = -w;
      s.a(2 * j + 1, 2 * j + 1) = -2 * md.damping_ratio * w;
      s.b0(2 * j + 1, axis) = sign * w / md.stiffness_n_per_mm;
      s.c(axis, 2 * j) = sign;
      ++j;
    }
  };
  add(structure.tool_x, 1, 0);
  add(structure.tool_y, 1, 1);
  add(structure.part_x, -1, 0);
  add(structure.part_y, -1, 1);
  const auto nn = static_cast<std::size_t>(s.n);
  const auto mm = static_cast<std::size_t>(s.m);
  s.p.assign(mm * nn * nn, 0.0);
  s.r0.assign(mm * nn * 2, 0.0);
  s.r1.assign(mm * nn * 2, 0.0);
  s.ubuf.assign(static_cast<std::size_t>(s.lag + s.m + 1) * 2, 0.0);
  s.xi = VectorXd::Zero(s.n);
  s.xi_next = VectorXd::Zero(s.n);
}

SdmSystem::~SdmSystem() = default;
SdmSystem::SdmSystem(SdmSystem&&) noexcept = default;
SdmSystem& SdmSystem::operator=(SdmSystem&&) noexcept = default;

int SdmSystem::intervals() const noexcept { return impl_->m; }
double SdmSystem::interval_s() const noexcept { return impl_->dt; }
int SdmSystem::dimension() const noexcept { return impl_->dim(); }

Multiplier SdmSystem::dominant(const std::vector<Mat2>& h_bar) {
  impl_->build(h_bar);
  return impl_->arnoldi();
}

Multiplier SdmSystem::dominant_dense(const std::vector<Mat2>& h_bar) {
  impl_->build(h_bar);
  return impl_->dense();
}

}  // namespace smc::machining::detail
