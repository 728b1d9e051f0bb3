#pragma once
// Structural models from a tap test: a measured frequency response function
// (compliance, displacement per force, against frequency: what impact-hammer
// test software exports) fitted to the modes of structure.hpp.
//
// Model of one measured direction: a sum of single-degree-of-freedom modes,
//   H(w) = sum_r 1 / (k_r (1 - (w/w_r)^2 + 2 i zeta_r w/w_r))   [mm/N]
// (the receptance of each Mode: q'' + 2 zeta w q' + w^2 q = (w^2 / k) F).
// The fit picks the peaks of |H| for the starting modes (frequency at the
// peak, damping from the half-power bandwidth, stiffness from the peak
// height), then refines every mode's frequency, damping and stiffness
// together by Levenberg-Marquardt (Eigen's) on the real and imaginary
// residuals.
//
// Not real-time (allocates, may throw).

#include <complex>
#include <map>
#include <string>
#include <vector>

#include "smc/machining/model.hpp"

namespace smc::machining {

struct FrfPoint {
  double frequency_hz = 0;
  std::complex<double> compliance_mm_per_n;
};

// One direction's FRF, in increasing frequency.
using Frf = std::vector<FrfPoint>;

// The receptance of `modes` at `frequency_hz` (mm/N).
std::complex<double> compliance(const std::vector<Mode>& modes, double frequency_hz);

struct ModalFit {
  std::vector<Mode> modes;  // by natural frequency
  double r_squared = 0;     // 1 - |residual|^2 / |H - mean H|^2, complex
  double rms_residual_mm_per_n = 0;
  int points = 0;
  int iterations = 0;
};

// Fits up to `max_modes` modes (the largest peaks of |H| at least
// `min_peak_share` of the highest). Throws std::invalid_argument naming the
// problem: fewer than 8 points, a frequency not positive or not increasing, a
// non-finite value, no peak.
ModalFit fit_modes(const Frf& frf, int max_modes = 3, double min_peak_share = 0.1);

// Reads a tap test's CSV: a header, then one row per frequency. Columns:
// frequency_hz, and for each measured direction D a pair D_real_U, D_imag_U
// where U is the unit of compliance: m_per_n, mm_per_n or um_per_n (e.g.
// "frequency_hz,x_real_m_per_n,x_imag_m_per_n,y_real_m_per_n,y_imag_m_per_n").
// Returns each direction's FRF in mm/N. Throws std::runtime_error
// "FILE:LINE: ..." naming the column and the fix.
std::map<std::string, Frf> read_frf_csv(const std::string& path);
// The same, from the file's text (`path` names it in messages).
std::map<std::string, Frf> parse_frf_csv(const std::string& text, const std::string& path);

}  // namespace smc::machining
