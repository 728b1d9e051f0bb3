#pragma once
// The static feed-force process model, eq. (1) of the paper:
//
//   F_Y = K d^beta f^alpha      F_Y in kN, d (depth) in mm, f (feed) in mm/tooth
//
// (paper: K = 0.76, beta = 0.65, alpha = 0.63). F_Y is the largest |F_y| over
// a spindle revolution. The functions here take and return newtons; the
// coefficient stays in kN as in the paper and the configuration document.
//
// Real-time use (the edge's model-based force controller): force_n() and
// feed_for_force_mm() are noexcept, allocation-free and return NaN for
// arguments out of their domain instead of throwing.

#include <cstdint>
#include <optional>
#include <span>

#include "smc/machining/model.hpp"

namespace smc::machining {

struct FitStatistics {
  std::uint32_t samples = 0;
  double r_squared = 0;       // 1 - SS_res / SS_tot of F_Y in newtons
  double rms_residual_n = 0;  // sqrt(SS_res / samples), newtons
  double k_stderr = 0;        // standard errors (kN for K; 0 for a fixed exponent)
  double beta_stderr = 0;
  double alpha_stderr = 0;
};

struct ForceProcessModel {
  double k_kn = 0;   // K > 0
  double beta = 0;   // depth exponent
  double alpha = 0;  // feed exponent (> 0 for the inverse to exist)
  Provenance provenance = Provenance::unspecified;
  bool validated = false;
  std::optional<FitStatistics> fit;  // present for a fitted model

  // F_Y (N) at depth d (mm) and feed f (mm/tooth). NaN if d or f < 0 or not finite.
  double force_n(double depth_mm, double feed_mm_per_tooth) const noexcept;
  // The process gain K d^beta (kN at f = 1 mm/tooth), the quantity the
  // paper's parameter estimator (module H) tracks.
  double gain_kn(double depth_mm) const noexcept;
  // The feed (mm/tooth) at which F_Y = target (N) at depth d: the inverse of
  // force_n. NaN if target <= 0, d <= 0, alpha == 0 or any input is not finite.
  double feed_for_force_mm(double depth_mm, double target_force_n) const noexcept;
};

// Checks k_kn > 0 and finite exponents; throws ModelError with paths under prefix.
void validate(const ForceProcessModel& model, const std::string& prefix = "force_model");

struct ForceSample {
  double depth_mm = 0;           // > 0
  double feed_mm_per_tooth = 0;  // > 0
  double force_n = 0;            // F_Y, > 0
};

struct FitOptions {
  // Hold an exponent instead of estimating it (needed when every sample has
  // the same depth, or the same feed: that exponent is then not identifiable).
  std::optional<double> fixed_beta;
  std::optional<double> fixed_alpha;
};

// Least squares on ln F_Y = ln K + beta ln d + alpha ln f (the model is linear
// in logarithms, so the fit is exact and unique when the design has rank).
// Standard errors are those of the log-linear regression (K's by the delta
// method); r_squared and the RMS residual are on F_Y in newtons. Throws
// std::invalid_argument naming the first bad sample ("samples[3].force_n:
// must be > 0, got -2"), too few samples for the free parameters, or a
// depth/feed that does not vary when its exponent is free.
ForceProcessModel fit_force_process(std::span<const ForceSample> samples,
                                    const FitOptions& options = {});

}  // namespace smc::machining
