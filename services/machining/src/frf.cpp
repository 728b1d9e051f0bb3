#include "smc/machining/frf.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unsupported/Eigen/LevenbergMarquardt>

namespace smc::machining {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

std::complex<double> mode_compliance(double omega_r, double zeta, double k, double omega) {
  const double s = omega / omega_r;
  return 1.0 / (k * std::complex<double>(1 - s * s, 2 * zeta * s));
}

// Residuals of the modes in x = [ln w_r, ln zeta_r, ln k_r]... against the
// measurement, real and imaginary parts, scaled by the largest |H|.
struct Residuals : Eigen::DenseFunctor<double> {
  const Frf* frf = nullptr;
  double scale = 1;
  Residuals(const Frf& f, int modes, double s)
      : Eigen::DenseFunctor<double>(3 * modes, 2 * static_cast<int>(f.size())), frf(&f), scale(s) {}
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    const int modes = static_cast<int>(x.size() / 3);
    for (std::size_t i = 0; i < frf->size(); ++i) {
      const double w = kTwoPi * (*frf)[i].frequency_hz;
      std::complex<double> h = 0;
      for (int r = 0; r < modes; ++r) {
        h += mode_compliance(std::exp(x[3 * r]), std::exp(x[3 * r + 1]), std::exp(x[3 * r + 2]), w);
      }
      const std::complex<double> e = (h - (*frf)[i].compliance_mm_per_n) / scale;
      fvec[static_cast<Eigen::Index>(2 * i)] = e.real();
      fvec[static_cast<Eigen::Index>(2 * i + 1)] = e.imag();
    }
    return 0;
  }
  // Analytic: with D = 1 - s^2 + 2 i zeta s, s = w / w_r and H_r = 1 / (k D),
  // dH_r/dln w_r = -H_r (2 s^2 - 2 i zeta s) / D, dH_r/dln zeta =
  // -H_r (2 i zeta s) / D, dH_r/dln k = -H_r.
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jac) const {
    const int modes = static_cast<int>(x.size() / 3);
    for (std::size_t i = 0; i < frf->size(); ++i) {
      const double w = kTwoPi * (*frf)[i].frequency_hz;
      const auto row = static_cast<Eigen::Index>(2 * i);
      for (int r = 0; r < modes; ++r) {
        const double wr = std::exp(x[3 * r]), z = std::exp(x[3 * r + 1]),
                     k = std::exp(x[3 * r + 2]);
        const double sr = w / wr;
        const std::complex<double> d(1 - sr * sr, 2 * z * sr);
        const std::complex<double> h = 1.0 / (k * d);
        const std::complex<double> dw = -h * std::complex<double>(2 * sr * sr, -2 * z * sr) / d;
        const std::complex<double> dz = -h * std::complex<double>(0, 2 * z * sr) / d;
        const std::complex<double> dk = -h;
        const Eigen::Index c = 3 * r;
        jac(row, c) = dw.real() / scale;
        jac(row + 1, c) = dw.imag() / scale;
        jac(row, c + 1) = dz.real() / scale;
        jac(row + 1, c + 1) = dz.imag() / scale;
        jac(row, c + 2) = dk.real() / scale;
        jac(row + 1, c + 2) = dk.imag() / scale;
      }
    }
    return 0;
  }
};

void check_frf(const Frf& frf) {
  if (frf.size() < 8) {
    throw std::invalid_argument(
        "FRF: " + std::to_string(frf.size()) +
        " points; a modal fit needs at least 8 (a tap test gives hundreds)");
  }
  for (std::size_t i = 0; i < frf.size(); ++i) {
    const auto& p = frf[i];
    if (!(std::isfinite(p.frequency_hz) && p.frequency_hz > 0)) {
      throw std::invalid_argument("FRF point " + std::to_string(i) + ": frequency must be > 0");
    }
    if (i > 0 && !(p.frequency_hz > frf[i - 1].frequency_hz)) {
      throw std::invalid_argument("FRF point " + std::to_string(i) +
                                  ": frequencies must increase (sort the file by frequency)");
    }
    if (!std::isfinite(p.compliance_mm_per_n.real()) ||
        !std::isfinite(p.compliance_mm_per_n.imag())) {
      throw std::invalid_argument("FRF point " + std::to_string(i) + ": compliance is not finite");
    }
  }
}

ModalFit fit_peaks(const Frf& frf, const std::vector<double>& mag,
                   const std::vector<std::size_t>& peaks, double top);

}  // namespace

std::complex<double> compliance(const std::vector<Mode>& modes, double frequency_hz) {
  std::complex<double> h = 0;
  for (const auto& m : modes) {
    h += mode_compliance(m.natural_frequency_rad_s, m.damping_ratio, m.stiffness_n_per_mm,
                         kTwoPi * frequency_hz);
  }
  return h;
}

ModalFit fit_modes(const Frf& frf, int max_modes, double min_peak_share) {
  check_frf(frf);
  if (max_modes < 1) throw std::invalid_argument("FRF fit: max_modes must be >= 1");
  const std::size_t n = frf.size();
  std::vector<double> mag;
  mag.reserve(n);
  double top = 0;
  for (const auto& p : frf) {
    mag.push_back(std::abs(p.compliance_mm_per_n));
    top = std::max(top, mag.back());
  }
  if (!(top > 0)) throw std::invalid_argument("FRF: the compliance is zero everywhere");

  // Peaks: local maxima of |H| over +-5 % in frequency, at least
  // min_peak_share of the highest, the largest first.
  std::vector<std::size_t> peaks;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (mag[i] < min_peak_share * top) continue;
    bool is_max = true;
    const double window = 0.05 * frf[i].frequency_hz;
    for (std::size_t j = i;
         j-- > 0 && is_max && frf[i].frequency_hz - frf[j].frequency_hz <= window;) {
      is_max = mag[j] <= mag[i];
    }
    for (std::size_t j = i + 1;
         j < n && is_max && frf[j].frequency_hz - frf[i].frequency_hz <= window; ++j) {
      is_max = mag[j] <= mag[i];
    }
    // A resonance falls below half power on both sides inside the band (a
    // noisy static plateau at low frequency does not).
    const double half = mag[i] / std::numbers::sqrt2;
    bool left = false, right = false;
    for (std::size_t j = i; j-- > 0 && !left;) left = mag[j] < half;
    for (std::size_t j = i + 1; j < n && !right; ++j) right = mag[j] < half;
    if (is_max && left && right) peaks.push_back(i);
  }
  if (peaks.empty()) {
    throw std::invalid_argument(
        "FRF: no resonance peak inside the measured band (widen the band around the modes)");
  }
  std::sort(peaks.begin(), peaks.end(), [&](auto a, auto b) { return mag[a] > mag[b]; });
  if (peaks.size() > static_cast<std::size_t>(max_modes)) {
    peaks.resize(static_cast<std::size_t>(max_modes));
  }
  // Noise the fit latched onto is not a mode: a resonance peak
  // (1 / (2 zeta k)) below half the smallest peak taken, or a half-power
  // bandwidth (2 zeta f) narrower than three frequency lines (this
  // measurement cannot resolve it).
  const double line_hz =
      (frf.back().frequency_hz - frf.front().frequency_hz) / static_cast<double>(frf.size() - 1);
  auto plausible = [&](const ModalFit& fit) {
    for (const auto& m : fit.modes) {
      const double f_hz = m.natural_frequency_rad_s / kTwoPi;
      if (1.0 / (2 * m.damping_ratio * m.stiffness_n_per_mm) < 0.5 * min_peak_share * top ||
          2 * m.damping_ratio * f_hz < 3 * line_hz) {
        return false;
      }
    }
    return true;
  };
  auto attempt = [&](const std::vector<std::size_t>& p) -> std::optional<ModalFit> {
    try {
      ModalFit fit = fit_peaks(frf, mag, p, top);
      if (plausible(fit)) return fit;
    } catch (const std::invalid_argument&) {
    }
    return std::nullopt;
  };
  // From the most peaks down: a mode is kept only when it pays for itself,
  // the fit without it leaving at least 20 % more residual (a mode fitted to
  // noise improves the fit by a few points' worth).
  std::optional<ModalFit> best;
  while (!peaks.empty()) {
    best = attempt(peaks);
    if (peaks.size() == 1) break;
    auto fewer = peaks;
    fewer.pop_back();
    const auto without = attempt(fewer);
    if (best && without &&
        without->rms_residual_mm_per_n * without->rms_residual_mm_per_n >
            1.2 * best->rms_residual_mm_per_n * best->rms_residual_mm_per_n) {
      return *best;
    }
    peaks = std::move(fewer);
  }
  if (!best) {
    throw std::invalid_argument(
        "FRF fit: the strongest peak did not fit an underdamped mode resolvable at this "
        "frequency resolution (a finer frequency step, or a cleaner measurement)");
  }
  return *best;
}

namespace {

ModalFit fit_peaks(const Frf& frf, const std::vector<double>& mag,
                   const std::vector<std::size_t>& peaks, double top) {
  const std::size_t n = frf.size();

  // Starting modes: frequency at the peak, damping from the half-power
  // bandwidth, stiffness from the height (|H| = 1 / (2 zeta k) at resonance).
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(peaks.size()));
  for (std::size_t r = 0; r < peaks.size(); ++r) {
    const std::size_t p = peaks[r];
    const double half = mag[p] / std::numbers::sqrt2;
    std::size_t lo = p, hi = p;
    while (lo > 0 && mag[lo] > half) --lo;
    while (hi + 1 < n && mag[hi] > half) ++hi;
    const double f = frf[p].frequency_hz;
    const double zeta =
        std::clamp((frf[hi].frequency_hz - frf[lo].frequency_hz) / (2 * f), 0.005, 0.5);
    const auto i = static_cast<Eigen::Index>(3 * r);
    x[i] = std::log(kTwoPi * f);
    x[i + 1] = std::log(zeta);
    x[i + 2] = std::log(1.0 / (2 * zeta * mag[p]));
  }

  Residuals f(frf, static_cast<int>(peaks.size()), top);
  Eigen::LevenbergMarquardt<Residuals> lm(f);
  lm.setMaxfev(300);
  lm.setXtol(1e-10);
  lm.setFtol(1e-10);
  lm.minimize(x);

  ModalFit fit;
  fit.points = static_cast<int>(n);
  fit.iterations = static_cast<int>(lm.iterations());
  for (std::size_t r = 0; r < peaks.size(); ++r) {
    const auto i = static_cast<Eigen::Index>(3 * r);
    Mode m;
    m.natural_frequency_rad_s = std::exp(x[i]);
    m.damping_ratio = std::exp(x[i + 1]);
    m.stiffness_n_per_mm = std::exp(x[i + 2]);
    if (!(m.damping_ratio < 1) || !std::isfinite(m.stiffness_n_per_mm)) {
      throw std::invalid_argument(
          "FRF fit: a mode did not converge to an underdamped mode (try fewer modes: "
          "--modes)");
    }
    fit.modes.push_back(m);
  }
  std::sort(fit.modes.begin(), fit.modes.end(), [](const Mode& a, const Mode& b) {
    return a.natural_frequency_rad_s < b.natural_frequency_rad_s;
  });
  std::complex<double> mean = 0;
  for (const auto& p : frf) mean += p.compliance_mm_per_n;
  mean /= static_cast<double>(n);
  double ss_res = 0, ss_tot = 0;
  for (const auto& p : frf) {
    ss_res += std::norm(compliance(fit.modes, p.frequency_hz) - p.compliance_mm_per_n);
    ss_tot += std::norm(p.compliance_mm_per_n - mean);
  }
  fit.r_squared = ss_tot > 0 ? 1 - ss_res / ss_tot : 0;
  fit.rms_residual_mm_per_n = std::sqrt(ss_res / static_cast<double>(n));
  return fit;
}

}  // namespace

std::map<std::string, Frf> read_frf_csv(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot read");
  std::ostringstream text;
  text << file.rdbuf();
  return parse_frf_csv(text.str(), path);
}

std::map<std::string, Frf> parse_frf_csv(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + ":1: empty file; fix: a header row");
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
      while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
      out.push_back(cell);
    }
    return out;
  };
  const auto header = split(line);
  const std::string fix =
      "; fix: columns frequency_hz, then D_real_U and D_imag_U per direction D, U one of m_per_n, "
      "mm_per_n, um_per_n (e.g. x_real_m_per_n,x_imag_m_per_n)";
  if (header.empty() || header[0] != "frequency_hz") {
    throw std::runtime_error(path + ":1: the first column must be frequency_hz" + fix);
  }
  struct Channel {
    std::string direction;
    std::size_t real = 0, imag = 0;
    double to_mm = 1;
  };
  std::map<std::string, Channel> channels;
  for (std::size_t c = 1; c < header.size(); ++c) {
    const std::string& h = header[c];
    double to_mm = 0;
    std::string stem;
    for (const auto& [suffix, factor] : {std::pair<std::string, double>{"_m_per_n", 1e3},
                                         {"_mm_per_n", 1.0},
                                         {"_um_per_n", 1e-3}}) {
      if (h.size() > suffix.size() &&
          h.compare(h.size() - suffix.size(), suffix.size(), suffix) == 0) {
        to_mm = factor;
        stem = h.substr(0, h.size() - suffix.size());
      }
    }
    const auto part = stem.rfind('_');
    if (to_mm == 0 || part == std::string::npos) {
      throw std::runtime_error(path + ":1: column '" + h + "' is not D_real_U or D_imag_U" + fix);
    }
    const std::string dir = stem.substr(0, part), what = stem.substr(part + 1);
    auto& ch = channels[dir];
    ch.direction = dir;
    if (ch.to_mm != 1 && ch.to_mm != to_mm) {
      throw std::runtime_error(path + ":1: direction '" + dir + "' mixes units" + fix);
    }
    ch.to_mm = to_mm;
    if (what == "real") {
      ch.real = c;
    } else if (what == "imag") {
      ch.imag = c;
    } else {
      throw std::runtime_error(path + ":1: column '" + h + "': '" + what +
                               "' is neither real nor imag" + fix);
    }
  }
  if (channels.empty()) throw std::runtime_error(path + ":1: no compliance columns" + fix);
  for (const auto& [dir, ch] : channels) {
    if (ch.real == 0 || ch.imag == 0) {
      throw std::runtime_error(path + ":1: direction '" + dir + "' needs both " + dir +
                               "_real_U and " + dir + "_imag_U" + fix);
    }
  }
  std::map<std::string, Frf> out;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty() || line == "\r") continue;
    const auto cells = split(line);
    if (cells.size() != header.size()) {
      throw std::runtime_error(path + ":" + std::to_string(row) + ": " +
                               std::to_string(cells.size()) + " values, the header has " +
                               std::to_string(header.size()));
    }
    auto number = [&](std::size_t c) {
      try {
        std::size_t used = 0;
        const double v = std::stod(cells[c], &used);
        if (used != cells[c].size() || !std::isfinite(v)) throw std::invalid_argument("");
        return v;
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(row) + ": " + header[c] + ": '" +
                                 cells[c] + "' is not a finite number");
      }
    };
    const double f = number(0);
    for (const auto& [dir, ch] : channels) {
      out[dir].push_back({f, {number(ch.real) * ch.to_mm, number(ch.imag) * ch.to_mm}});
    }
  }
  for (auto& [dir, frf] : out) {
    try {
      check_frf(frf);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(path + ": direction '" + dir + "': " + e.what());
    }
  }
  if (out.empty()) throw std::runtime_error(path + ": no data rows after the header");
  return out;
}

}  // namespace smc::machining
