#pragma once
// First-order semi-discretization of xi' = A xi - B H(t) C (xi(t) - xi(t - tau))
// (internal; see lobes.hpp for the method and its sources).

#include <array>
#include <complex>
#include <memory>
#include <vector>

#include "smc/machining/lobes.hpp"
#include "smc/machining/model.hpp"

namespace smc::machining::detail {

using Mat2 = std::array<double, 4>;  // row-major xx, xy, yx, yy

class SdmSystem {
 public:
  // period_s: T; delay_periods: tau / T; intervals: m per period.
  SdmSystem(const Structure& structure, double period_s, int delay_periods, int intervals);
  ~SdmSystem();
  SdmSystem(SdmSystem&&) noexcept;
  SdmSystem& operator=(SdmSystem&&) noexcept;

  int intervals() const noexcept;
  double interval_s() const noexcept;
  int dimension() const noexcept;  // of the monodromy matrix

  // Dominant Floquet multiplier with H_i the mean of H over interval i
  // (intervals() entries).
  Multiplier dominant(const std::vector<Mat2>& h_bar);
  // The same from the dense monodromy matrix (slow; for checks).
  Multiplier dominant_dense(const std::vector<Mat2>& h_bar);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

BoundaryKind classify(std::complex<double> mu) noexcept;

}  // namespace smc::machining::detail
