#include "smc/machining/lobes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "format.hpp"
#include "sdm.hpp"
#include "smc/machining/cutting.hpp"

namespace smc::machining {

namespace {

using detail::Mat2;
constexpr double kPi = std::numbers::pi;

// 8-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr std::array<double, 8> kGlNode = {
    -0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
    0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
constexpr std::array<double, 8> kGlWeight = {
    0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
    0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

// H(t) of the milling cut, split as H = d^pt Ht + d^pr Hr (tangential and
// radial parts of the tangent cutting stiffness at unit depth factor).
struct MillingLinearisation {
  std::vector<Mat2> ht, hr;
  double pt = 1, pr = 1;
  double tooth_period_s = 0;

  std::vector<Mat2> at(double depth_mm) const {
    const double a = std::pow(depth_mm, pt);
    const double b = std::pow(depth_mm, pr);
    std::vector<Mat2> out(ht.size());
    for (std::size_t i = 0; i < ht.size(); ++i) {
      for (std::size_t k = 0; k < 4; ++k) out[i][k] = a * ht[i][k] + b * hr[i][k];
    }
    return out;
  }
};

double highest_frequency_hz(const Structure& s) {
  double w = 0;
  for (const auto* axis : {&s.tool_x, &s.tool_y, &s.part_x, &s.part_y}) {
    for (const Mode& m : *axis) w = std::max(w, m.natural_frequency_rad_s);
  }
  return w / (2 * kPi);
}

int auto_intervals(const MillingModel& model, double rpm, const SdmOptions& o) {
  if (o.intervals > 0) return o.intervals;
  const double period = tooth_period_s(rpm, model.cutter.teeth);
  const Engagement e = engagement(model.cutter, model.workpiece);
  const double pitch = 2 * kPi / model.cutter.teeth;
  const double frac = e.engaged ? std::min(1.0, (e.high_rad - e.low_rad) / pitch) : 1.0;
  double m = o.min_intervals;
  m = std::max(
      m, std::ceil(o.intervals_per_mode_period * highest_frequency_hz(model.structure) * period));
  m = std::max(m, std::ceil(o.intervals_in_cut / std::max(frac, 1e-3)));
  return static_cast<int>(std::min<double>(m, o.max_intervals));
}

MillingLinearisation linearise(const MillingModel& model, double rpm, double feed_mm, int m) {
  MillingLinearisation lin;
  const int n_teeth = model.cutter.teeth;
  const double period = tooth_period_s(rpm, n_teeth);
  lin.tooth_period_s = period;
  if (const auto* p = std::get_if<PowerLaw>(&model.law)) {
    lin.pt = 1 + p->cutting.depth_exponent;
    lin.pr = 1 + p->thrust.depth_exponent;
  }
  const Engagement e = engagement(model.cutter, model.workpiece);
  const double s = rotation_sense(model.workpiece);
  const double omega = 2 * kPi * rpm / 60.0;
  const double v = cutting_speed_m_per_min(model.cutter.radius_mm, rpm);
  const double dt = period / m;
  lin.ht.assign(static_cast<std::size_t>(m), Mat2{0, 0, 0, 0});
  lin.hr.assign(static_cast<std::size_t>(m), Mat2{0, 0, 0, 0});
  if (!e.engaged) return lin;
  for (int i = 0; i < m; ++i) {
    Mat2& ht = lin.ht[static_cast<std::size_t>(i)];
    Mat2& hr = lin.hr[static_cast<std::size_t>(i)];
    const double t0 = i * dt;
    const double t1 = (i + 1) * dt;
    for (int j = 0; j < n_teeth; ++j) {
      const double a0 = s * omega * t0 + 2 * kPi * j / n_teeth;
      const double a1 = s * omega * t1 + 2 * kPi * j / n_teeth;
      const double lo = std::min(a0, a1);
      const double hi = std::max(a0, a1);
      const auto k_first = static_cast<int>(std::floor((lo - e.high_rad) / (2 * kPi)));
      const auto k_last = static_cast<int>(std::ceil((hi - e.low_rad) / (2 * kPi)));
      for (int k = k_first; k <= k_last; ++k) {
        const double b0 = std::max(lo, e.low_rad + 2 * kPi * k);
        const double b1 = std::min(hi, e.high_rad + 2 * kPi * k);
        if (!(b1 > b0)) continue;
        const double half = (b1 - b0) / 2;
        const double mid = (b1 + b0) / 2;
        for (std::size_t g = 0; g < kGlNode.size(); ++g) {
          const double th = mid + half * kGlNode[g];
          const double w = half * kGlWeight[g] / (hi - lo);
          const double c = std::cos(th);
          const double sn = std::sin(th);
          const CuttingStiffness ks =
              tangent_stiffness(model.law, model.cutter.lead_angle_deg, feed_mm * c, 1.0, v);
          // H = (k_r r + k_t t) r^T, r = (c, sn), t = s (-sn, c).
          const double tx = -s * sn;
          const double ty = s * c;
          ht[0] += w * ks.tangential_n_per_mm * tx * c;
          ht[1] += w * ks.tangential_n_per_mm * tx * sn;
          ht[2] += w * ks.tangential_n_per_mm * ty * c;
          ht[3] += w * ks.tangential_n_per_mm * ty * sn;
          hr[0] += w * ks.radial_n_per_mm * c * c;
          hr[1] += w * ks.radial_n_per_mm * c * sn;
          hr[2] += w * ks.radial_n_per_mm * sn * c;
          hr[3] += w * ks.radial_n_per_mm * sn * sn;
        }
      }
    }
  }
  return lin;
}

// One speed's semi-discretised system(s) and linearised cut(s).
struct SpeedProblem {
  SpeedProblem(const MillingModel& model, double rpm, double feed, const SdmOptions& o)
      : intervals(auto_intervals(model, rpm, o)),
        extrapolate(o.extrapolate),
        lin(linearise(model, rpm, feed, intervals)),
        system(model.structure, lin.tooth_period_s, delay_periods(model), intervals) {
    if (extrapolate) {
      lin_fine = linearise(model, rpm, feed, 2 * intervals);
      system_fine = std::make_unique<detail::SdmSystem>(model.structure, lin.tooth_period_s,
                                                        delay_periods(model), 2 * intervals);
    }
  }

  static int delay_periods(const MillingModel& model) {
    return model.delay == DelayKind::tooth_period ? 1 : model.cutter.teeth;
  }

  Multiplier at(double depth) {
    ++evaluations;
    const Multiplier coarse = system.dominant(lin.at(depth));
    if (!extrapolate) return coarse;
    Multiplier fine = system_fine->dominant(lin_fine.at(depth));
    fine.magnitude = std::max(0.0, (4 * fine.magnitude - coarse.magnitude) / 3);
    return fine;
  }

  int intervals;
  bool extrapolate;
  MillingLinearisation lin, lin_fine;
  detail::SdmSystem system;
  std::unique_ptr<detail::SdmSystem> system_fine;
  int evaluations = 0;
};

LobePoint make_point(double rpm, double depth, const Multiplier& mu, double period, int m) {
  LobePoint p;
  p.spindle_rpm = rpm;
  p.critical_depth_mm = depth;
  p.kind = mu.kind;
  p.base_chatter_frequency_hz = std::abs(std::arg(mu.value)) / (2 * kPi * period);
  p.intervals = m;
  return p;
}

// Illinois (modified regula falsi) on |mu| - 1 within [lo, hi] (stable lo,
// unstable hi), with a bisection whenever two steps did not halve the bracket.
LobePoint refine(SpeedProblem& sp, double rpm, double lo, double g_lo, double hi, double g_hi,
                 Multiplier mu_hi, const SdmOptions& o) {
  int side = 0;
  double width_before = hi - lo;
  for (int it = 0; it < 100 && (hi - lo) > o.relative_tolerance * lo; ++it) {
    double c = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
    if (it % 2 == 1) {
      if (hi - lo > 0.5 * width_before) c = 0.5 * (lo + hi);
      width_before = hi - lo;
    }
    // Never closer to an end than a quarter of the tolerance.
    const double guard = 0.25 * o.relative_tolerance * lo;
    c = std::clamp(c, lo + guard, hi - guard);
    if (!(c > lo && c < hi)) c = 0.5 * (lo + hi);
    const Multiplier mu = sp.at(c);
    const double g = mu.magnitude - 1;
    if (g >= 0) {
      hi = c;
      g_hi = g;
      mu_hi = mu;
      if (side == 1) g_lo /= 2;
      side = 1;
    } else {
      lo = c;
      g_lo = g;
      if (side == -1) g_hi /= 2;
      side = -1;
    }
  }
  return make_point(rpm, 0.5 * (lo + hi), mu_hi, sp.lin.tooth_period_s, sp.intervals);
}

LobePoint none_point(double rpm, const SdmOptions& o, const SpeedProblem& sp,
                     const Multiplier& mu) {
  LobePoint p = make_point(rpm, o.max_depth_mm, mu, sp.lin.tooth_period_s, sp.intervals);
  p.kind = BoundaryKind::none;
  p.base_chatter_frequency_hz = 0;
  return p;
}

// From the bottom up: the lowest boundary.
LobePoint search_from_below(SpeedProblem& sp, double rpm, const SdmOptions& o) {
  double lo = o.max_depth_mm / 4096;
  Multiplier mu = sp.at(lo);
  double g_lo = mu.magnitude - 1;
  if (g_lo >= 0) {
    // Unstable at the smallest depth tried: go lower still.
    double hi = lo;
    double g_hi = g_lo;
    Multiplier mu_hi = mu;
    for (int i = 0; i < 20; ++i) {
      lo = hi / 4;
      mu = sp.at(lo);
      g_lo = mu.magnitude - 1;
      if (g_lo < 0) return refine(sp, rpm, lo, g_lo, hi, g_hi, mu_hi, o);
      hi = lo;
      g_hi = g_lo;
      mu_hi = mu;
    }
    return make_point(rpm, hi, mu_hi, sp.lin.tooth_period_s, sp.intervals);
  }
  for (;;) {
    const double hi = std::min(lo * 2, o.max_depth_mm);
    const Multiplier mu_hi = sp.at(hi);
    const double g_hi = mu_hi.magnitude - 1;
    if (g_hi >= 0) return refine(sp, rpm, lo, g_lo, hi, g_hi, mu_hi, o);
    if (hi >= o.max_depth_mm) return none_point(rpm, o, sp, mu_hi);
    lo = hi;
    g_lo = g_hi;
  }
}

// From a guess (the neighbouring speeds' boundary): a bracket grown in
// widening steps around it, then refine().
LobePoint search_near(SpeedProblem& sp, double rpm, double guess, const SdmOptions& o) {
  guess = std::clamp(guess, o.max_depth_mm / 4096, o.max_depth_mm);
  const Multiplier mu0 = sp.at(guess);
  const double g0 = mu0.magnitude - 1;
  double step = 1.03;
  if (g0 < 0) {
    double lo = guess, g_lo = g0;
    for (;;) {
      if (lo >= o.max_depth_mm) return none_point(rpm, o, sp, mu0);
      const double hi = std::min(lo * step, o.max_depth_mm);
      const Multiplier mu = sp.at(hi);
      const double g = mu.magnitude - 1;
      if (g >= 0) return refine(sp, rpm, lo, g_lo, hi, g, mu, o);
      if (hi >= o.max_depth_mm) return none_point(rpm, o, sp, mu);
      lo = hi;
      g_lo = g;
      step = std::min(step * step, 1.5);
    }
  }
  double hi = guess, g_hi = g0;
  Multiplier mu_hi = mu0;
  for (int i = 0; i < 60; ++i) {
    const double lo = hi / step;
    if (lo < o.max_depth_mm / 4096) break;
    const Multiplier mu = sp.at(lo);
    const double g = mu.magnitude - 1;
    if (g < 0) return refine(sp, rpm, lo, g, hi, g_hi, mu_hi, o);
    hi = lo;
    g_hi = g;
    mu_hi = mu;
    step = std::min(step * step, 1.5);
  }
  return search_from_below(sp, rpm, o);
}

void check_options(const SdmOptions& o) {
  if (o.intervals < 0 || o.min_intervals < 1 || o.max_intervals < o.min_intervals ||
      !(o.intervals_per_mode_period > 0) || !(o.intervals_in_cut > 0) || !(o.max_depth_mm > 0) ||
      !(o.relative_tolerance > 0 && o.relative_tolerance < 0.5)) {
    throw std::invalid_argument(
        "semi-discretization options: need intervals >= 0, 1 <= min_intervals <= "
        "max_intervals, positive interval densities, max_depth_mm > 0, relative_tolerance in "
        "(0, 0.5)");
  }
}

void check_cut(const MillingModel& model, double rpm, double feed) {
  validate(model);
  validate(CutConditions{rpm, feed, 0});
  if (std::holds_alternative<PowerLaw>(model.law) && !(feed > 0)) {
    throw std::invalid_argument(
        "feed_per_tooth_mm: must be > 0 for a power-law model (the tangent cutting stiffness "
        "depends on the chip), got " +
        detail::fmt(feed));
  }
}

}  // namespace

const char* to_string(BoundaryKind kind) noexcept {
  switch (kind) {
    case BoundaryKind::hopf:
      return "hopf";
    case BoundaryKind::flip:
      return "flip";
    case BoundaryKind::fold:
      return "fold";
    case BoundaryKind::none:
      return "none";
  }
  return "?";
}

Multiplier dominant_multiplier(const MillingModel& model, const CutConditions& cut,
                               const SdmOptions& options) {
  check_options(options);
  check_cut(model, cut.spindle_rpm, cut.feed_per_tooth_mm);
  if (!(cut.depth_mm > 0)) {
    throw std::invalid_argument("cut.depth_mm: must be > 0, got " + detail::fmt(cut.depth_mm));
  }
  SpeedProblem sp(model, cut.spindle_rpm, cut.feed_per_tooth_mm, options);
  return sp.at(cut.depth_mm);
}

int sdm_intervals(const MillingModel& model, double spindle_rpm, const SdmOptions& options) {
  check_options(options);
  check_cut(model, spindle_rpm, 0.1);
  return auto_intervals(model, spindle_rpm, options);
}

LobePoint critical_depth_sdm(const MillingModel& model, double spindle_rpm,
                             double feed_per_tooth_mm, const SdmOptions& options) {
  check_options(options);
  check_cut(model, spindle_rpm, feed_per_tooth_mm);
  SpeedProblem sp(model, spindle_rpm, feed_per_tooth_mm, options);
  return search_from_below(sp, spindle_rpm, options);
}

std::vector<LobePoint> stability_lobes(const MillingModel& model, const LobeOptions& options) {
  check_options(options.sdm);
  if (!(options.rpm_min > 0 && options.rpm_max >= options.rpm_min && options.speeds >= 1 &&
        std::isfinite(options.rpm_max))) {
    throw std::invalid_argument("lobes: need 0 < rpm_min <= rpm_max and speeds >= 1, got rpm_min " +
                                detail::fmt(options.rpm_min) + ", rpm_max " +
                                detail::fmt(options.rpm_max) + ", speeds " +
                                std::to_string(options.speeds));
  }
  check_cut(model, options.rpm_min, options.feed_per_tooth_mm);
  std::vector<LobePoint> out;
  out.reserve(static_cast<std::size_t>(options.speeds));
  for (int i = 0; i < options.speeds; ++i) {
    const double rpm = options.speeds == 1 ? options.rpm_min
                                           : options.rpm_min + (options.rpm_max - options.rpm_min) *
                                                                   i / (options.speeds - 1);
    SpeedProblem sp(model, rpm, options.feed_per_tooth_mm, options.sdm);
    LobePoint p;
    if (out.empty()) {
      p = search_from_below(sp, rpm, options.sdm);
    } else if (out.back().kind == BoundaryKind::none) {
      const Multiplier top = sp.at(options.sdm.max_depth_mm);
      p = top.magnitude < 1 ? none_point(rpm, options.sdm, sp, top)
                            : search_from_below(sp, rpm, options.sdm);
    } else {
      // Extrapolate along the current lobe from the last two points.
      double guess = out.back().critical_depth_mm;
      if (out.size() >= 2 && out[out.size() - 2].kind != BoundaryKind::none) {
        const double ratio = guess / out[out.size() - 2].critical_depth_mm;
        guess *= std::clamp(ratio, 0.8, 1.25);
      }
      p = search_near(sp, rpm, guess, options.sdm);
    }
    out.push_back(p);
    if (options.on_progress) options.on_progress(i + 1, options.speeds);
  }
  return out;
}

Multiplier dominant_multiplier(const LinearisedCut& cut, int intervals, bool extrapolate) {
  if (!cut.mean_directional) {
    throw std::invalid_argument("LinearisedCut.mean_directional: not set");
  }
  if (!(cut.period_s > 0) || cut.delay_periods < 1 || intervals < 1) {
    throw std::invalid_argument(
        "LinearisedCut: need period_s > 0, delay_periods >= 1 and intervals >= 1");
  }
  const auto at = [&cut](int m) {
    detail::SdmSystem system(cut.structure, cut.period_s, cut.delay_periods, m);
    std::vector<Mat2> h(static_cast<std::size_t>(m));
    const double dt = cut.period_s / m;
    for (int i = 0; i < m; ++i) {
      h[static_cast<std::size_t>(i)] = cut.mean_directional(i * dt, (i + 1) * dt);
    }
    return system.dominant(h);
  };
  const Multiplier coarse = at(intervals);
  if (!extrapolate) return coarse;
  Multiplier fine = at(2 * intervals);
  fine.magnitude = std::max(0.0, (4 * fine.magnitude - coarse.magnitude) / 3);
  return fine;
}

}  // namespace smc::machining
