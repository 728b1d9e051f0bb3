#include "smc/machining/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "engine.hpp"
#include "format.hpp"
#include "multiversion.hpp"

namespace smc::machining {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kResyncCalls = 4096;

std::size_t history_for(const MillingModel& model, double min_rpm, double step_s) {
  const double longest = delay_s(model, min_rpm);
  return static_cast<std::size_t>(std::ceil(longest / step_s)) + 4;
}
}  // namespace

struct MillSimulator::Impl {
  Impl(const MillingModel& m, const SimulatorOptions& o, double h, int steps)
      : model(m),
        options(o),
        step_s(h),
        steps_per_sample(steps),
        teeth(m.cutter.teeth),
        engine(m, h, history_for(m, o.min_spindle_rpm, h)),
        position_mm(o.initial_tool_position_mm) {
    max_delay_steps = static_cast<double>(engine.history_capacity() - 3);
  }

  // One sample (MillSimulator::step); trace: nullptr or where the force of
  // each internal step goes.
  SMC_MULTIVERSION static std::uint32_t step(Impl& s, const SampleInput& input, Sample& out,
                                             const StepForceTrace* trace) noexcept;

  MillingModel model;
  SimulatorOptions options;
  double step_s;
  int steps_per_sample;
  int teeth;
  detail::CutEngine engine;
  double max_delay_steps = 0;
  double position_mm;
  double spindle_angle_rad = 0;  // tooth 0
  std::int64_t samples = 0;
  // Cached per input (feedrate, rpm, depth) (NaN: nothing cached yet).
  double in_feedrate = kNaN, in_rpm = kNaN, in_depth = kNaN;
  double feed_tooth = 0, v_m_s = 0, dx = 0, delay_steps = 0, half_sweep = 0;
  bool below_min_spindle = false;
  double dtheta = kNaN, rc = 1, rs = 0, hc = 1, hs = 0;
  double dir_c = 1, dir_s = 0;  // tooth 0's direction at the end of the last sample
  int calls_since_sync = 0;
};

MillSimulator::MillSimulator(const MillingModel& model, const SimulatorOptions& options) {
  validate(model);
  if (!(std::isfinite(options.sample_period_s) && options.sample_period_s > 0 &&
        options.sample_period_s <= 1.0)) {
    throw std::invalid_argument("simulator options.sample_period_s: must be in (0, 1] s, got " +
                                detail::fmt(options.sample_period_s));
  }
  if (!(std::isfinite(options.min_spindle_rpm) && options.min_spindle_rpm >= 1)) {
    throw std::invalid_argument("simulator options.min_spindle_rpm: must be >= 1, got " +
                                detail::fmt(options.min_spindle_rpm));
  }
  if (!(std::isfinite(options.initial_tool_position_mm))) {
    throw std::invalid_argument("simulator options.initial_tool_position_mm: must be finite");
  }
  double bound =
      options.max_internal_step_s > 0 ? options.max_internal_step_s : model.internal_step_s;
  if (!(std::isfinite(bound) && bound > 0 && bound <= kMaxInternalStepS)) {
    throw std::invalid_argument(
        "simulator options.max_internal_step_s: must be in (0, 1e-4], got " + detail::fmt(bound));
  }
  const double n = std::ceil(options.sample_period_s / bound - 1e-9);
  if (n > 1e6) throw std::invalid_argument("simulator: more than 1e6 internal steps per sample");
  const int steps = std::max(1, static_cast<int>(n));
  const double h = options.sample_period_s / steps;
  impl_ = std::make_unique<Impl>(model, options, h, steps);
}

MillSimulator::~MillSimulator() = default;
MillSimulator::MillSimulator(MillSimulator&&) noexcept = default;
MillSimulator& MillSimulator::operator=(MillSimulator&&) noexcept = default;

std::uint32_t MillSimulator::step(const SampleInput& input, Sample& out) noexcept {
  return Impl::step(*impl_, input, out, nullptr);
}

std::uint32_t MillSimulator::step(const SampleInput& input, Sample& out,
                                  const StepForceTrace& trace) noexcept {
  return Impl::step(*impl_, input, out, &trace);
}

std::uint32_t MillSimulator::Impl::step(Impl& s, const SampleInput& input, Sample& out,
                                        const StepForceTrace* trace) noexcept {
  std::uint32_t status = 0;
  double feedrate = input.feedrate_mm_s;
  double rpm = input.spindle_rpm;
  double depth = input.depth_mm;
  if (!(std::isfinite(feedrate) && feedrate >= 0 && std::isfinite(rpm) && rpm >= 0 &&
        std::isfinite(depth) && depth >= 0)) {
    status |= StepStatus::kInvalidInput;
    feedrate = 0;
    rpm = 0;
    depth = 0;
  }
  // Everything that depends only on the inputs is cached, and recomputed
  // (pow, sin and cos calls among it) only when an input changes: a
  // caller stepping at constant conditions pays none of it.
  if (feedrate != s.in_feedrate || rpm != s.in_rpm || depth != s.in_depth) {
    s.in_feedrate = feedrate;
    s.in_rpm = rpm;
    s.in_depth = depth;
    s.feed_tooth = feed_per_tooth_mm(feedrate, rpm, s.teeth);
    s.engine.set_operating_point(rpm, s.feed_tooth, depth);
    s.v_m_s = cutting_speed_m_per_s(s.engine.radius_mm(), rpm);
    s.dx = feedrate * s.step_s;
    s.delay_steps = rpm > 0 ? delay_s(s.model, rpm) / s.step_s : 0;
    s.below_min_spindle = s.delay_steps > s.max_delay_steps;
    if (s.below_min_spindle) s.delay_steps = s.max_delay_steps;
    // The spindle's rotation per step; tooth 0's direction is kept as a unit
    // vector rotated step by step (resynchronised from the angle when the
    // speed changes and every 4096 calls).
    const double dtheta = s.engine.sense() * kTwoPi * rpm / 60.0 * s.step_s;
    if (dtheta != s.dtheta) {
      s.dtheta = dtheta;
      s.rc = std::cos(dtheta);
      s.rs = std::sin(dtheta);
      s.hc = std::cos(dtheta / 2);
      s.hs = std::sin(dtheta / 2);
      s.calls_since_sync = kResyncCalls;
    }
    s.half_sweep = std::abs(dtheta) / 2;
  }
  if (s.below_min_spindle) status |= StepStatus::kBelowMinSpindle;
  if (rpm == 0 && feedrate > 0 && depth > 0) {
    // Feeding with the spindle stopped: a crash if the cutter overlaps the part.
    const double r = s.engine.radius_mm();
    if (s.position_mm + r >= 0 && s.position_mm - r <= s.model.workpiece.length_mm) {
      status |= StepStatus::kSpindleStoppedInCut;
    }
  }
  if (++s.calls_since_sync >= kResyncCalls) {
    s.dir_c = std::cos(s.spindle_angle_rad);
    s.dir_s = std::sin(s.spindle_angle_rad);
    s.calls_since_sync = 0;
  }
  // Tooth 0 at the middle of the first step.
  double c0 = s.dir_c * s.hc - s.dir_s * s.hs;
  double s0 = s.dir_s * s.hc + s.dir_c * s.hs;
  const double v_m_s = s.v_m_s;
  const double dx = s.dx;
  const double delay_steps = s.delay_steps;
  const double half_sweep = s.half_sweep;

  double power_sum = 0;
  double max_abs_fy = 0;
  detail::StepForces last;
  for (int k = 0; k < s.steps_per_sample; ++k) {
    last = s.engine.step(c0, s0, s.position_mm + dx / 2, true, delay_steps, half_sweep,
                         s.options.regenerative);
    if (trace != nullptr) {
      const auto i = static_cast<std::size_t>(k);
      trace->fx_n[i] = last.fx_n;
      trace->fy_n[i] = last.fy_n;
      trace->fz_n[i] = last.fz_n;
      if (trace->vibration_y_mm != nullptr) {
        const Displacements d = s.engine.structure().displacements();
        trace->vibration_y_mm[i] = d.tool_y_mm - d.part_y_mm;
      }
    }
    s.position_mm += dx;
    power_sum += last.tangential_sum_n * v_m_s;
    max_abs_fy = std::max(max_abs_fy, std::abs(last.fy_n));
    const double c1 = c0 * s.rc - s0 * s.rs;
    s0 = s0 * s.rc + c0 * s.rs;
    c0 = c1;
  }
  // (c0, s0) is now the middle of the next step: back half a step.
  s.dir_c = c0 * s.hc + s0 * s.hs;
  s.dir_s = s0 * s.hc - c0 * s.hs;
  s.spindle_angle_rad += s.dtheta * s.steps_per_sample;
  if (std::abs(s.spindle_angle_rad) > 4 * kTwoPi) {
    s.spindle_angle_rad = std::remainder(s.spindle_angle_rad, kTwoPi);
  }
  ++s.samples;

  // Subnormal numbers only appear after a long ring-down: every 64 calls is enough.
  if ((s.samples & 63) == 0) s.engine.structure().flush_tiny();
  if (!s.engine.structure().finite()) {
    status |= StepStatus::kNotFinite;
    s.engine.reset();
    power_sum = 0;
    max_abs_fy = 0;
    last = detail::StepForces{};
    if (trace != nullptr) {
      // No non-finite value leaves: a caller's filters would keep it forever.
      for (std::size_t i = 0; i < static_cast<std::size_t>(s.steps_per_sample); ++i) {
        trace->fx_n[i] = trace->fy_n[i] = trace->fz_n[i] = 0;
        if (trace->vibration_y_mm != nullptr) trace->vibration_y_mm[i] = 0;
      }
    }
  }

  // Outputs at the sample instant.
  detail::StepForces now = last;
  if (s.options.forces_at_sample_instant) {
    now = s.engine.forces_now(s.dir_c, s.dir_s, s.position_mm, true, delay_steps,
                              s.options.regenerative);
  }
  const Displacements d = s.engine.structure().displacements();
  out.time_s = static_cast<double>(s.samples) * s.options.sample_period_s;
  out.fx_n = now.fx_n;
  out.fy_n = now.fy_n;
  out.fz_n = now.fz_n;
  out.power_w = now.tangential_sum_n * v_m_s;
  out.mean_power_w = power_sum / s.steps_per_sample;
  out.max_abs_fy_n = std::max(max_abs_fy, std::abs(now.fy_n));
  out.tool_x_mm = d.tool_x_mm;
  out.tool_y_mm = d.tool_y_mm;
  out.part_x_mm = d.part_x_mm;
  out.part_y_mm = d.part_y_mm;
  out.tool_position_mm = s.position_mm;
  out.feed_per_tooth_mm = s.feed_tooth;
  out.teeth_in_cut = now.teeth_cutting;
  out.status = status;
  return status;
}

void MillSimulator::set_tool_position(double x_mm) noexcept {
  if (std::isfinite(x_mm)) impl_->position_mm = x_mm;
}

double MillSimulator::tool_position_mm() const noexcept { return impl_->position_mm; }

void MillSimulator::set_tooth_runout_mm(int tooth, double runout_mm) noexcept {
  impl_->engine.set_runout_mm(tooth, runout_mm);
}
double MillSimulator::tooth_runout_mm(int tooth) const noexcept {
  return impl_->engine.runout_mm(tooth);
}
void MillSimulator::set_force_scale(double scale) noexcept {
  impl_->engine.set_force_scale(scale);
  impl_->in_feedrate = kNaN;  // the next step recomputes the operating point with it
}

void MillSimulator::reset() noexcept {
  Impl& s = *impl_;
  s.engine.reset();
  s.position_mm = s.options.initial_tool_position_mm;
  s.spindle_angle_rad = 0;
  s.samples = 0;
  s.in_feedrate = s.in_rpm = s.in_depth = kNaN;
  s.dtheta = kNaN;
  s.dir_c = 1;
  s.dir_s = 0;
  s.calls_since_sync = 0;
}

double MillSimulator::time_s() const noexcept {
  return static_cast<double>(impl_->samples) * impl_->options.sample_period_s;
}
double MillSimulator::internal_step_s() const noexcept { return impl_->step_s; }
int MillSimulator::steps_per_sample() const noexcept { return impl_->steps_per_sample; }
double MillSimulator::sample_period_s() const noexcept { return impl_->options.sample_period_s; }
const MillingModel& MillSimulator::model() const noexcept { return impl_->model; }

}  // namespace smc::machining
