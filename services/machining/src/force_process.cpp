#include "smc/machining/force_process.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "format.hpp"

namespace smc::machining {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double ForceProcessModel::force_n(double depth_mm, double feed_mm_per_tooth) const noexcept {
  if (!(std::isfinite(depth_mm) && depth_mm >= 0 && std::isfinite(feed_mm_per_tooth) &&
        feed_mm_per_tooth >= 0)) {
    return kNaN;
  }
  if (depth_mm == 0 || feed_mm_per_tooth == 0) return 0;
  return 1000.0 * k_kn * std::pow(depth_mm, beta) * std::pow(feed_mm_per_tooth, alpha);
}

double ForceProcessModel::gain_kn(double depth_mm) const noexcept {
  if (!(std::isfinite(depth_mm) && depth_mm > 0)) return kNaN;
  return k_kn * std::pow(depth_mm, beta);
}

double ForceProcessModel::feed_for_force_mm(double depth_mm, double target_force_n) const noexcept {
  if (!(std::isfinite(depth_mm) && depth_mm > 0 && std::isfinite(target_force_n) &&
        target_force_n > 0 && alpha != 0 && k_kn > 0)) {
    return kNaN;
  }
  const double gain_n = 1000.0 * k_kn * std::pow(depth_mm, beta);
  return std::pow(target_force_n / gain_n, 1.0 / alpha);
}

void validate(const ForceProcessModel& m, const std::string& prefix) {
  std::vector<std::string> errors;
  if (!(std::isfinite(m.k_kn) && m.k_kn > 0)) {
    errors.push_back(prefix + ".k_kn: must be > 0, got " + detail::fmt(m.k_kn));
  }
  if (!std::isfinite(m.beta)) errors.push_back(prefix + ".beta: must be finite");
  if (!std::isfinite(m.alpha)) errors.push_back(prefix + ".alpha: must be finite");
  if (!errors.empty()) throw ModelError(std::move(errors));
}

ForceProcessModel fit_force_process(std::span<const ForceSample> samples,
                                    const FitOptions& options) {
  const bool free_beta = !options.fixed_beta.has_value();
  const bool free_alpha = !options.fixed_alpha.has_value();
  if (!free_beta && !std::isfinite(*options.fixed_beta)) {
    throw std::invalid_argument("fit options.fixed_beta: must be finite");
  }
  if (!free_alpha && !std::isfinite(*options.fixed_alpha)) {
    throw std::invalid_argument("fit options.fixed_alpha: must be finite");
  }
  const int params = 1 + (free_beta ? 1 : 0) + (free_alpha ? 1 : 0);
  const auto n = static_cast<Eigen::Index>(samples.size());
  if (n < params) {
    throw std::invalid_argument("samples: " + std::to_string(samples.size()) + " given, at least " +
                                std::to_string(params) + " needed for the free parameters");
  }
  Eigen::MatrixXd x(n, params);
  Eigen::VectorXd y(n);
  double min_d = std::numeric_limits<double>::infinity(), max_d = -min_d;
  double min_f = min_d, max_f = -min_d;
  for (Eigen::Index i = 0; i < n; ++i) {
    const ForceSample& s = samples[static_cast<std::size_t>(i)];
    const std::string path = "samples[" + std::to_string(i) + "]";
    if (!(std::isfinite(s.depth_mm) && s.depth_mm > 0)) {
      throw std::invalid_argument(path + ".depth_mm: must be > 0, got " + detail::fmt(s.depth_mm));
    }
    if (!(std::isfinite(s.feed_mm_per_tooth) && s.feed_mm_per_tooth > 0)) {
      throw std::invalid_argument(path + ".feed_mm_per_tooth: must be > 0, got " +
                                  detail::fmt(s.feed_mm_per_tooth));
    }
    if (!(std::isfinite(s.force_n) && s.force_n > 0)) {
      throw std::invalid_argument(path + ".force_n: must be > 0, got " + detail::fmt(s.force_n));
    }
    const double ld = std::log(s.depth_mm);
    const double lf = std::log(s.feed_mm_per_tooth);
    min_d = std::min(min_d, ld);
    max_d = std::max(max_d, ld);
    min_f = std::min(min_f, lf);
    max_f = std::max(max_f, lf);
    double yi = std::log(s.force_n / 1000.0);
    Eigen::Index c = 0;
    x(i, c++) = 1.0;
    if (free_beta) {
      x(i, c++) = ld;
    } else {
      yi -= *options.fixed_beta * ld;
    }
    if (free_alpha) {
      x(i, c++) = lf;
    } else {
      yi -= *options.fixed_alpha * lf;
    }
    y(i) = yi;
  }
  if (free_beta && max_d - min_d < 1e-9) {
    throw std::invalid_argument(
        "samples: every sample has the same depth, so beta cannot be estimated: give "
        "FitOptions::fixed_beta");
  }
  if (free_alpha && max_f - min_f < 1e-9) {
    throw std::invalid_argument(
        "samples: every sample has the same feed, so alpha cannot be estimated: give "
        "FitOptions::fixed_alpha");
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  if (qr.rank() < params) {
    throw std::invalid_argument(
        "samples: depth and feed vary together (ln d and ln f collinear), so beta and alpha "
        "cannot be told apart: fix one of them");
  }
  const Eigen::VectorXd coef = qr.solve(y);
  ForceProcessModel m;
  Eigen::Index c = 0;
  m.k_kn = std::exp(coef(c++));
  m.beta = free_beta ? coef(c++) : *options.fixed_beta;
  m.alpha = free_alpha ? coef(c++) : *options.fixed_alpha;
  m.provenance = Provenance::fitted;

  // Statistics.
  const Eigen::VectorXd log_residual = y - x * coef;
  const double dof = static_cast<double>(n - params);
  const double s2 = dof > 0 ? log_residual.squaredNorm() / dof : 0.0;
  const Eigen::MatrixXd cov = s2 * (x.transpose() * x).inverse();
  FitStatistics st;
  st.samples = static_cast<std::uint32_t>(n);
  c = 0;
  st.k_stderr = m.k_kn * std::sqrt(cov(c, c));
  ++c;
  if (free_beta) {
    st.beta_stderr = std::sqrt(cov(c, c));
    ++c;
  }
  if (free_alpha) st.alpha_stderr = std::sqrt(cov(c, c));
  double mean = 0;
  for (const ForceSample& s : samples) mean += s.force_n;
  mean /= static_cast<double>(n);
  double ss_res = 0, ss_tot = 0;
  for (const ForceSample& s : samples) {
    const double e = s.force_n - m.force_n(s.depth_mm, s.feed_mm_per_tooth);
    ss_res += e * e;
    ss_tot += (s.force_n - mean) * (s.force_n - mean);
  }
  st.rms_residual_n = std::sqrt(ss_res / static_cast<double>(n));
  st.r_squared = ss_tot > 0 ? 1.0 - ss_res / ss_tot : (ss_res == 0 ? 1.0 : 0.0);
  m.fit = st;
  return m;
}

}  // namespace smc::machining
