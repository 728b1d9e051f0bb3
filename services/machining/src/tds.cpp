#include "smc/machining/tds.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "engine.hpp"
#include "format.hpp"
#include "multiversion.hpp"

namespace smc::machining {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kSettledRatio = 1e-9;

struct RunSetup {
  int steps_per_period = 0;  // m
  double step_s = 0;
  int delay_steps = 0;
};

RunSetup setup_for(const MillingModel& model, double rpm, double max_step) {
  const double bound = max_step > 0 ? max_step : model.internal_step_s;
  if (!(std::isfinite(bound) && bound > 0 && bound <= kMaxInternalStepS)) {
    throw std::invalid_argument("max_internal_step_s: must be in (0, 1e-4], got " +
                                detail::fmt(bound));
  }
  const double period = tooth_period_s(rpm, model.cutter.teeth);
  const double m = std::ceil(period / bound - 1e-9);
  if (m > 5e6) {
    throw std::invalid_argument("a tooth period of " + detail::fmt(period) + " s (" +
                                detail::fmt(rpm) + " rpm) is " + detail::fmt(m) +
                                " internal steps of " + detail::fmt(bound) +
                                " s, more than 5e6: raise the spindle speed or the internal step");
  }
  RunSetup s;
  s.steps_per_period = std::max(1, static_cast<int>(m));
  s.step_s = period / s.steps_per_period;
  s.delay_steps = model.delay == DelayKind::tooth_period ? s.steps_per_period
                                                         : s.steps_per_period * model.cutter.teeth;
  return s;
}

// A mode's periodic (steady) response to a force sequence repeated forever:
// the state at the start of a period, z* = (I - Phi^m)^-1 w, with w the
// response over one period from rest and Phi^m the period's transition.
void steady_response(const DiscreteMode& md, const std::vector<double>& force, double& q_star,
                     double& v_star) {
  double q = 0, v = 0;                        // response from rest
  double a11 = 1, a12 = 0, a21 = 0, a22 = 1;  // Phi^m
  for (const double fk : force) {
    const double f = md.sign * fk;
    const double q1 = md.p11 * q + md.p12 * v + md.g1 * f;
    v = md.p21 * q + md.p22 * v + md.g2 * f;
    q = q1;
    const double b11 = md.p11 * a11 + md.p12 * a21, b12 = md.p11 * a12 + md.p12 * a22;
    const double b21 = md.p21 * a11 + md.p22 * a21, b22 = md.p21 * a12 + md.p22 * a22;
    a11 = b11;
    a12 = b12;
    a21 = b21;
    a22 = b22;
  }
  const double m11 = 1 - a11, m12 = -a12, m21 = -a21, m22 = 1 - a22;
  const double det = m11 * m22 - m12 * m21;
  q_star = (m22 * q - m12 * v) / det;
  v_star = (m11 * v - m21 * q) / det;
}

// ln D_k against k over [first, last): least-squares slope.
double log_slope(const std::vector<double>& d, std::size_t first, std::size_t last) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = first; k < last; ++k) {
    if (!(d[k] > 0)) continue;
    const double x = static_cast<double>(k);
    const double y = std::log(d[k]);
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double den = n * sxx - sx * sx;
  if (n < 3 || den <= 0) return std::numeric_limits<double>::quiet_NaN();
  return (n * sxy - sx * sy) / den;
}

// Rest start: the verdict from D_k (see tds.hpp).
StabilityReport judge_from_rest(const std::vector<double>& d, const std::vector<char>& jumped,
                                bool settled, const std::string& period) {
  StabilityReport r;
  r.periods = static_cast<int>(d.size());
  r.settled = settled;
  r.multiplier = std::numeric_limits<double>::quiet_NaN();
  r.growth_per_period = r.multiplier;
  if (d.empty()) {
    r.reason = "no " + period + " simulated";
    return r;
  }
  const std::size_t k = d.size();
  r.growth_per_period = log_slope(d, k / 2, k);
  r.multiplier = std::exp(r.growth_per_period);
  for (std::size_t i = k - k / 4; i < k; ++i) {
    if (jumped[i]) r.teeth_jumped_out = true;
  }
  if (settled) {
    r.verdict = Verdict::stable;
    r.reason = "settled: the once-per-" + period + " state stopped changing";
  } else if (r.teeth_jumped_out) {
    r.verdict = Verdict::unstable;
    r.reason = "chatter: teeth left the cut mid-engagement late in the run";
  } else if (std::isnan(r.growth_per_period)) {
    r.verdict = Verdict::stable;
    r.reason = "too short to judge";
  } else if (r.growth_per_period >= 0) {
    r.verdict = Verdict::unstable;
    r.reason = "chatter: the vibration grows by " + detail::fmt(r.growth_per_period) +
               " (ln) per " + period;
  } else {
    r.verdict = Verdict::stable;
    r.reason = "stable: the vibration decays by " + detail::fmt(-r.growth_per_period) +
               " (ln) per " + period;
  }
  return r;
}

// The dominant multiplier of the linear map fitted to successive columns
// (exact dynamic mode decomposition with rank truncation): the eigenvalue
// whose mode carries the largest share of the last sample. (Not simply the
// largest eigenvalue: the power law's curvature makes a weak component that
// grows like mu^2, which the fit also finds.)
double fitted_multiplier(const Eigen::MatrixXd& samples) {
  const Eigen::Index w = samples.cols() - 1;
  if (w < 2) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::MatrixXd x = samples.leftCols(w);
  const Eigen::MatrixXd y = samples.rightCols(w);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(x, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  Eigen::Index r = 0;
  while (r < sv.size() && sv(r) > 1e-8 * sv(0)) ++r;
  if (r == 0) return 0;
  const Eigen::MatrixXd u = svd.matrixU().leftCols(r);
  const Eigen::MatrixXd v = svd.matrixV().leftCols(r);
  const Eigen::MatrixXd a = u.transpose() * y * v * sv.head(r).cwiseInverse().asDiagonal();
  const Eigen::EigenSolver<Eigen::MatrixXd> es(a, true);
  const Eigen::MatrixXcd modes = es.eigenvectors();
  // Amplitudes of the modes in the last sample.
  const Eigen::VectorXcd last = (u.transpose() * samples.col(w)).cast<std::complex<double>>();
  const Eigen::VectorXcd b = modes.fullPivLu().solve(last);
  double best_amplitude = -1, rho = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double amplitude = std::abs(b(i)) * modes.col(i).norm();
    if (amplitude > best_amplitude * (1 + 1e-9)) {
      best_amplitude = amplitude;
      rho = std::abs(es.eigenvalues()(i));
    }
  }
  return rho;
}

constexpr double kDecayed = 1e-6;  // deviation / its largest value: stable
constexpr double kGrown = 1e4;     // deviation / disturbance: unstable
constexpr int kFitWindow = 64;     // last samples the map is fitted to

StabilityReport judge_on_orbit(const std::vector<double>& norms, const Eigen::MatrixXd& states,
                               bool settled, bool grew, const std::vector<char>& jumped,
                               const std::string& period) {
  StabilityReport r;
  r.periods = static_cast<int>(norms.size());
  r.settled = settled;
  r.grew = grew;
  r.multiplier = std::numeric_limits<double>::quiet_NaN();
  r.growth_per_period = r.multiplier;
  const std::size_t k = norms.size();
  for (std::size_t i = k - k / 4; i < k; ++i) {
    if (jumped[i]) r.teeth_jumped_out = true;
  }
  if (settled) {
    r.verdict = Verdict::stable;
    r.reason = "stable: the disturbance of the steady cut died out (decayed by 1e6)";
    return r;
  }
  if (grew) {
    r.verdict = Verdict::unstable;
    r.reason = "chatter: the disturbance of the steady cut grew by 1e4";
    return r;
  }
  const Eigen::Index cols = std::min<Eigen::Index>(states.cols(), kFitWindow);
  r.multiplier = fitted_multiplier(states.rightCols(cols));
  r.growth_per_period = std::log(r.multiplier);
  if (!(r.multiplier >= 0)) {
    r.verdict = Verdict::unstable;
    r.reason = "no estimate of the growth (the state is not finite)";
  } else if (r.multiplier < 1) {
    r.verdict = Verdict::stable;
    r.reason = "stable: disturbances decay by " + detail::fmt(r.multiplier) + " per " + period;
  } else {
    r.verdict = Verdict::unstable;
    r.reason = "chatter: disturbances grow by " + detail::fmt(r.multiplier) + " per " + period;
  }
  return r;
}

}  // namespace

namespace {
SMC_MULTIVERSION BatchResult run_batch(const MillingModel& model, const CutConditions& cut,
                                       const BatchOptions& options);
}  // namespace

BatchResult simulate(const MillingModel& model, const CutConditions& cut,
                     const BatchOptions& options) {
  return run_batch(model, cut, options);
}

namespace {

BatchResult run_batch(const MillingModel& model, const CutConditions& cut,
                      const BatchOptions& options) {
  validate(model);
  validate(cut);
  if (options.start_on_steady_cut && has_runout(model.cutter)) {
    // With runout the chatter-free motion repeats only every revolution and
    // the one-tooth delay regenerates it (u(t) - u(t - T) != 0): it is not
    // the structure's response to the nominal forces, and this criterion
    // has no orbit to start on. Runout is a forcing at the spindle's
    // harmonics; to first order it leaves the regenerative dynamics as they
    // are, so the verdict is that of the same cut without runout (README.md,
    // "Runout"). Runs from rest (below) keep the runout.
    MillingModel plain = model;
    plain.cutter.radial_runout_um.clear();
    BatchResult r = run_batch(plain, cut, options);
    r.stability.reason += " (judged without the cutter's runout)";
    return r;
  }
  if (!(std::isfinite(options.duration_s) && options.duration_s > 0)) {
    throw std::invalid_argument("batch options.duration_s: must be > 0, got " +
                                detail::fmt(options.duration_s));
  }
  if (!(std::isfinite(options.record_every_s) && options.record_every_s >= 0)) {
    throw std::invalid_argument("batch options.record_every_s: must be >= 0");
  }
  if (!std::isfinite(options.start_position_mm)) {
    throw std::invalid_argument("batch options.start_position_mm: must be finite");
  }
  if (options.start_on_steady_cut && !options.steady) {
    throw std::invalid_argument(
        "batch options.start_on_steady_cut: needs steady = true (a cut that enters the part "
        "has no periodic motion to start on)");
  }
  if (!(std::isfinite(options.disturbance_mm) && options.disturbance_mm >= 0)) {
    throw std::invalid_argument("batch options.disturbance_mm: must be >= 0");
  }
  const RunSetup su = setup_for(model, cut.spindle_rpm, options.max_internal_step_s);
  const int n_teeth = model.cutter.teeth;
  const int m = su.steps_per_period;
  const double h = su.step_s;

  detail::CutEngine engine(model, h, static_cast<std::size_t>(su.delay_steps) + 4);
  engine.set_operating_point(cut.spindle_rpm, cut.feed_per_tooth_mm, cut.depth_mm);
  const int sense = engine.sense();

  // Mid-step angles over one revolution: exactly periodic.
  const int per_rev = m * n_teeth;
  // The cut repeats every tooth period; with runout the teeth differ, and
  // it repeats only every revolution: a run from rest then compares the
  // state once per revolution.
  const bool runout = engine.runout();
  const int section = runout ? per_rev : m;
  const std::string period_name = runout ? "revolution" : "tooth period";
  const double half_sweep = std::numbers::pi / per_rev;  // half of 2 pi / per_rev
  std::vector<double> table_cos(static_cast<std::size_t>(per_rev));
  std::vector<double> table_sin(static_cast<std::size_t>(per_rev));
  for (int j = 0; j < per_rev; ++j) {
    const double a = sense * kTwoPi * (j + 0.5) / per_rev;
    table_cos[static_cast<std::size_t>(j)] = std::cos(a);
    table_sin[static_cast<std::size_t>(j)] = std::sin(a);
  }
  // Tooth 0's direction at the middle of step `phase` (in [0, per_rev)); the
  // engine turns it to the other teeth.
  double tc = 1, ts = 0;
  const auto angles = [&](std::int64_t phase) {
    tc = table_cos[static_cast<std::size_t>(phase)];
    ts = table_sin[static_cast<std::size_t>(phase)];
  };

  const double feedrate = cut.feed_per_tooth_mm * n_teeth * cut.spindle_rpm / 60.0;
  const double dx = options.steady ? 0.0 : feedrate * h;
  double position = options.steady ? 0.0 : options.start_position_mm;
  const bool check_length = !options.steady;
  const double v_m_s = cutting_speed_m_per_s(model.cutter.radius_mm, cut.spindle_rpm);
  const double delay_steps = su.delay_steps;
  StructureModel& st = engine.structure();
  const std::size_t modes = st.size();

  // The periodic (chatter-free) motion: each mode's steady response to the
  // nominal forces, z* = (I - Phi^m)^-1 w, w the response over one period
  // from rest. Then one delay of it is run to fill the history, and the
  // state is disturbed.
  std::vector<double> orbit_q(modes, 0.0), orbit_v(modes, 0.0);
  if (options.start_on_steady_cut) {
    const std::int64_t start_phase = (per_rev - su.delay_steps % per_rev) % per_rev;
    std::vector<double> fx(static_cast<std::size_t>(section)), fy(fx.size());
    for (int k = 0; k < section; ++k) {
      angles((start_phase + k) % per_rev);
      const detail::StepForces f = engine.tooth_forces(tc, ts, 0.0, false, 0.0, 0.0, half_sweep);
      fx[static_cast<std::size_t>(k)] = f.fx_n;
      fy[static_cast<std::size_t>(k)] = f.fy_n;
    }
    for (std::size_t i = 0; i < modes; ++i) {
      const DiscreteMode& md = st.mode(i);
      steady_response(md, md.axis == Axis::x ? fx : fy, orbit_q[i], orbit_v[i]);
      st.set_state(i, orbit_q[i], orbit_v[i]);
    }
    const std::size_t last = static_cast<std::size_t>(section - 1);
    engine.set_previous_force(fx[last], fy[last]);
    for (int k = 0; k < su.delay_steps; ++k) {
      angles((start_phase + k) % per_rev);
      engine.step(tc, ts, 0.0, false, delay_steps, half_sweep, false);
    }
    for (std::size_t i = 0; i < modes; ++i) {
      orbit_q[i] = st.q(i);  // back on the orbit (up to rounding)
      orbit_v[i] = st.v(i);
      st.set_state(i, st.q(i) + options.disturbance_mm, st.v(i));
    }
  }

  const double total = std::ceil(options.duration_s / h - 1e-9);
  if (total > 2e9) throw std::invalid_argument("batch options.duration_s: too many steps");
  const auto steps = static_cast<std::int64_t>(total);
  const auto max_periods = static_cast<std::size_t>(total / section);
  const std::int64_t record_every =
      options.record_every_s > 0
          ? std::max<std::int64_t>(1, std::llround(options.record_every_s / h))
          : 0;

  BatchResult out;
  out.internal_step_s = h;
  out.steps_per_tooth_period = m;
  if (record_every > 0) {
    const auto n = static_cast<std::size_t>(steps / record_every + 1);
    for (auto* v : {&out.time_s, &out.fx_n, &out.fy_n, &out.fz_n, &out.power_w, &out.tool_x_mm,
                    &out.tool_y_mm, &out.part_x_mm, &out.part_y_mm, &out.tool_position_mm}) {
      v->reserve(n);
    }
    out.teeth_in_cut.reserve(n);
  }

  // Poincare section of the modal state (q, v / omega) once per tooth period.
  std::vector<double> inv_omega(modes);
  for (std::size_t i = 0; i < modes; ++i) inv_omega[i] = 1.0 / st.mode(i).natural_frequency_rad_s;
  std::vector<double> last_q(orbit_q), last_v(orbit_v);
  Eigen::MatrixXd states;  // deviations, one column per period (orbit start)
  if (options.start_on_steady_cut) {
    states.resize(static_cast<Eigen::Index>(2 * modes), static_cast<Eigen::Index>(max_periods + 1));
  }
  std::vector<char> jumped;
  bool settled = false, grew = false;
  bool period_jumped = false;
  double power_total = 0;
  double first_norm = 0, max_norm = 0;
  const auto section_sample = [&](Eigen::Index col) {
    double sum = 0;
    for (std::size_t i = 0; i < modes; ++i) {
      double dq, dv;
      if (options.start_on_steady_cut) {
        dq = st.q(i) - orbit_q[i];
        dv = (st.v(i) - orbit_v[i]) * inv_omega[i];
        states(static_cast<Eigen::Index>(2 * i), col) = dq;
        states(static_cast<Eigen::Index>(2 * i + 1), col) = dv;
      } else {
        dq = st.q(i) - last_q[i];
        dv = (st.v(i) - last_v[i]) * inv_omega[i];
        last_q[i] = st.q(i);
        last_v[i] = st.v(i);
      }
      sum += dq * dq + dv * dv;
    }
    return std::sqrt(sum);
  };
  if (options.start_on_steady_cut) first_norm = max_norm = section_sample(0);

  std::int64_t phase = 0;  // k mod per_rev
  int in_period = 0;       // k mod section
  std::int64_t record_countdown = record_every;
  for (std::int64_t k = 0; k < steps; ++k) {
    angles(phase);
    if (++phase == per_rev) phase = 0;
    const detail::StepForces f =
        engine.step(tc, ts, position + dx / 2, check_length, delay_steps, half_sweep);
    position += dx;
    power_total += f.tangential_sum_n * v_m_s;
    out.max_abs_fy_n = std::max(out.max_abs_fy_n, std::abs(f.fy_n));
    if (f.jumped_out) period_jumped = true;

    const std::int64_t done = k + 1;
    if (record_every > 0 && --record_countdown == 0) {
      record_countdown = record_every;
      // Tooth 0's angle at the end of this step.
      const double a0 = sense * kTwoPi * static_cast<double>(done % per_rev) / per_rev;
      const detail::StepForces fn =
          engine.forces_now(std::cos(a0), std::sin(a0), position, check_length, delay_steps);
      const Displacements d = st.displacements();
      out.time_s.push_back(static_cast<double>(done) * h);
      out.fx_n.push_back(fn.fx_n);
      out.fy_n.push_back(fn.fy_n);
      out.fz_n.push_back(fn.fz_n);
      out.power_w.push_back(fn.tangential_sum_n * v_m_s);
      out.tool_x_mm.push_back(d.tool_x_mm);
      out.tool_y_mm.push_back(d.tool_y_mm);
      out.part_x_mm.push_back(d.part_x_mm);
      out.part_y_mm.push_back(d.part_y_mm);
      out.tool_position_mm.push_back(position);
      out.teeth_in_cut.push_back(fn.teeth_cutting);
    }

    if (++in_period == section) {
      in_period = 0;
      st.flush_tiny();
      const double dk = section_sample(static_cast<Eigen::Index>(out.section.size() + 1));
      out.section.push_back(dk);
      jumped.push_back(period_jumped ? 1 : 0);
      period_jumped = false;
      if (!std::isfinite(dk)) break;
      max_norm = std::max(max_norm, dk);
      if (options.start_on_steady_cut) {
        if (first_norm > 0 && dk <= kDecayed * max_norm) settled = true;
        if (first_norm > 0 && dk >= kGrown * first_norm) grew = true;
        if (dk == 0) settled = true;  // no disturbance and no change
      } else if (out.section.size() > 2 && dk <= kSettledRatio * max_norm) {
        settled = true;
      }
      if (options.stop_when_decided) {
        if (settled || grew) break;
        if (!options.start_on_steady_cut) {
          // Saturated chatter: teeth jumping out in each of the last two
          // revolutions, after the first quarter of the run.
          const std::size_t np = out.section.size();
          const auto window = static_cast<std::size_t>(runout ? 2 : 2 * n_teeth);
          if (np > std::max(window, max_periods / 4)) {
            bool all = true;
            for (std::size_t i = np - window; i < np && all; ++i) all = jumped[i] != 0;
            if (all) break;
          }
        }
      }
    }
  }
  out.mean_power_w = steps > 0 ? power_total / static_cast<double>(steps) : 0;
  if (options.start_on_steady_cut) {
    out.stability = judge_on_orbit(
        out.section, states.leftCols(static_cast<Eigen::Index>(out.section.size() + 1)), settled,
        grew, jumped, period_name);
  } else {
    out.stability = judge_from_rest(out.section, jumped, settled, period_name);
  }
  return out;
}

}  // namespace

StabilityReport assess_stability(const MillingModel& model, const CutConditions& cut,
                                 int tooth_periods, double max_internal_step_s) {
  if (tooth_periods < 8)
    throw std::invalid_argument("assess_stability: tooth_periods must be >= 8");
  BatchOptions o;
  o.duration_s = tooth_periods * tooth_period_s(cut.spindle_rpm, model.cutter.teeth);
  o.max_internal_step_s = max_internal_step_s;
  o.record_every_s = 0;
  o.steady = true;
  o.stop_when_decided = true;
  o.start_on_steady_cut = true;
  o.disturbance_mm = 1e-5 * std::max(cut.feed_per_tooth_mm, 1e-3);
  return simulate(model, cut, o).stability;
}

TdsSearchResult critical_depth_tds(const MillingModel& model, double spindle_rpm,
                                   double feed_per_tooth_mm, const TdsSearchOptions& options) {
  validate(model);
  validate(CutConditions{spindle_rpm, feed_per_tooth_mm, 0});
  if (!(feed_per_tooth_mm > 0)) {
    throw std::invalid_argument("critical_depth_tds: feed_per_tooth_mm must be > 0, got " +
                                detail::fmt(feed_per_tooth_mm));
  }
  if (!(options.min_depth_mm > 0 && options.max_depth_mm > options.min_depth_mm &&
        options.initial_depth_mm > 0 && options.relative_tolerance > 0)) {
    throw std::invalid_argument(
        "critical_depth_tds: need 0 < min_depth_mm < max_depth_mm, initial_depth_mm > 0 and "
        "relative_tolerance > 0");
  }
  TdsSearchResult r;
  const auto probe = [&](double depth) {
    const StabilityReport s =
        assess_stability(model, CutConditions{spindle_rpm, feed_per_tooth_mm, depth},
                         options.tooth_periods, options.max_internal_step_s);
    DepthProbe p{depth, s.verdict == Verdict::stable, s.growth_per_period};
    r.probes.push_back(p);
    if (options.on_probe) options.on_probe(p);
    return p.stable;
  };
  double d = std::clamp(options.initial_depth_mm, options.min_depth_mm, options.max_depth_mm);
  double lo = 0, hi = 0;  // stable, unstable
  if (probe(d)) {
    lo = d;
    for (;;) {
      if (lo >= options.max_depth_mm) {
        r.critical_depth_mm = r.stable_depth_mm = options.max_depth_mm;
        r.unstable_depth_mm = std::numeric_limits<double>::infinity();
        return r;
      }
      const double next = std::min(lo * 2, options.max_depth_mm);
      if (probe(next)) {
        lo = next;
      } else {
        hi = next;
        break;
      }
    }
  } else {
    hi = d;
    for (;;) {
      if (hi <= options.min_depth_mm) {
        r.critical_depth_mm = r.unstable_depth_mm = options.min_depth_mm;
        r.stable_depth_mm = 0;
        return r;
      }
      const double next = std::max(hi / 2, options.min_depth_mm);
      if (probe(next)) {
        lo = next;
        break;
      }
      hi = next;
    }
  }
  while ((hi - lo) > options.relative_tolerance * lo) {
    const double mid = 0.5 * (lo + hi);
    if (probe(mid)) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  r.bounded = true;
  r.stable_depth_mm = lo;
  r.unstable_depth_mm = hi;
  r.critical_depth_mm = 0.5 * (lo + hi);
  return r;
}

}  // namespace smc::machining
