#include "smc/machining/model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "format.hpp"

namespace smc::machining {

double feed_per_tooth_mm(double feedrate_mm_s, double spindle_rpm, int teeth) noexcept {
  if (!(spindle_rpm > 0) || teeth < 1) return 0;
  return feedrate_mm_s * 60.0 / (spindle_rpm * teeth);
}

double tooth_period_s(double spindle_rpm, int teeth) noexcept {
  return 60.0 / (spindle_rpm * std::max(teeth, 1));
}

double delay_s(const MillingModel& model, double spindle_rpm) noexcept {
  return model.delay == DelayKind::tooth_period ? tooth_period_s(spindle_rpm, model.cutter.teeth)
                                                : 60.0 / spindle_rpm;
}

bool has_runout(const Cutter& cutter) noexcept {
  for (const double r : cutter.radial_runout_um) {
    if (r != 0) return true;
  }
  return false;
}

std::vector<double> eccentric_runout_um(int teeth, double amplitude_um, double phase_deg) {
  if (teeth < 1) throw std::invalid_argument("eccentric_runout_um: teeth must be >= 1");
  if (!std::isfinite(amplitude_um) || !std::isfinite(phase_deg)) {
    throw std::invalid_argument("eccentric_runout_um: amplitude and phase must be finite");
  }
  std::vector<double> r(static_cast<size_t>(teeth));
  const double phase = phase_deg * std::numbers::pi / 180.0;
  for (int i = 0; i < teeth; ++i) {
    r[static_cast<size_t>(i)] = amplitude_um * std::cos(2 * std::numbers::pi * i / teeth - phase);
  }
  return r;
}

namespace {

std::string join_lines(const std::vector<std::string>& errors) {
  std::string out;
  for (std::size_t i = 0; i < errors.size(); ++i) {
    if (i) out += '\n';
    out += errors[i];
  }
  return out;
}

// Collects "path: message, got value" lines.
class Checker {
 public:
  explicit Checker(std::vector<std::string>& out) : out_(out) {}
  void positive(const std::string& path, double v) {
    if (!(std::isfinite(v) && v > 0)) fail(path, "must be > 0", v);
  }
  void non_negative(const std::string& path, double v) {
    if (!(std::isfinite(v) && v >= 0)) fail(path, "must be >= 0", v);
  }
  void finite(const std::string& path, double v) {
    if (!std::isfinite(v)) fail(path, "must be finite", v);
  }
  void open_range(const std::string& path, double v, double lo, double hi) {
    if (!(std::isfinite(v) && v > lo && v < hi)) {
      fail(path, "must be in (" + detail::fmt(lo) + ", " + detail::fmt(hi) + ")", v);
    }
  }
  void greater(const std::string& path, double v, double lo) {
    if (!(std::isfinite(v) && v > lo)) fail(path, "must be > " + detail::fmt(lo), v);
  }
  void fail(const std::string& path, const std::string& what, double v) {
    out_.push_back(path + ": " + what + ", got " + detail::fmt(v));
  }
  void fail(const std::string& path, const std::string& what) {
    out_.push_back(path + ": " + what);
  }

 private:
  std::vector<std::string>& out_;
};

void check_pressure(Checker& c, const std::string& path, const PressureLaw& p) {
  c.positive(path + ".coefficient_kn_per_mm2", p.coefficient_kn_per_mm2);
  c.greater(path + ".feed_exponent", p.feed_exponent, -1);
  c.greater(path + ".depth_exponent", p.depth_exponent, -1);
  c.finite(path + ".speed_exponent", p.speed_exponent);
}

}  // namespace

ModelError::ModelError(std::vector<std::string> errors)
    : std::invalid_argument(join_lines(errors)), errors_(std::move(errors)) {}

std::vector<std::string> validation_errors(const MillingModel& m, const std::string& prefix) {
  std::vector<std::string> errors;
  Checker c(errors);
  const std::string cp = prefix + ".cutter";
  if (m.cutter.teeth < 1) c.fail(cp + ".teeth", "must be >= 1", m.cutter.teeth);
  c.positive(cp + ".radius_mm", m.cutter.radius_mm);
  if (!(std::isfinite(m.cutter.lead_angle_deg) && m.cutter.lead_angle_deg >= 0 &&
        m.cutter.lead_angle_deg < 90)) {
    c.fail(cp + ".lead_angle_deg", "must be in [0, 90)", m.cutter.lead_angle_deg);
  }
  const auto& runout = m.cutter.radial_runout_um;
  if (!runout.empty() && static_cast<int>(runout.size()) != m.cutter.teeth) {
    c.fail(cp + ".radial_runout_um", "needs one value per tooth (" +
                                         std::to_string(m.cutter.teeth) + "), or none; got " +
                                         std::to_string(runout.size()));
  }
  for (size_t i = 0; i < runout.size(); ++i) {
    if (!(std::isfinite(runout[i]) && std::fabs(runout[i]) <= kMaxRunoutUm)) {
      c.fail(cp + ".radial_runout_um[" + std::to_string(i) + "]",
             "must be within +-" + detail::fmt(kMaxRunoutUm) + " um", runout[i]);
    }
  }
  const std::string wp = prefix + ".workpiece";
  c.positive(wp + ".width_mm", m.workpiece.width_mm);
  c.finite(wp + ".offset_mm", m.workpiece.offset_mm);
  c.positive(wp + ".length_mm", m.workpiece.length_mm);
  const bool geometry_known = std::isfinite(m.workpiece.width_mm) && m.workpiece.width_mm > 0 &&
                              std::isfinite(m.workpiece.offset_mm) &&
                              std::isfinite(m.cutter.radius_mm) && m.cutter.radius_mm > 0;
  if (geometry_known) {
    const double lo = m.workpiece.offset_mm - m.workpiece.width_mm / 2;
    const double hi = m.workpiece.offset_mm + m.workpiece.width_mm / 2;
    if (lo >= m.cutter.radius_mm || hi <= -m.cutter.radius_mm) {
      c.fail(wp + ".offset_mm",
             "puts the part's width band [" + detail::fmt(lo) + ", " + detail::fmt(hi) +
                 "] mm outside the cutter's reach (radius " + detail::fmt(m.cutter.radius_mm) +
                 " mm): the teeth never cut",
             m.workpiece.offset_mm);
    }
  }
  const std::string lp = prefix + ".law";
  if (const auto* p = std::get_if<PowerLaw>(&m.law)) {
    check_pressure(c, lp + ".power_law.cutting", p->cutting);
    check_pressure(c, lp + ".power_law.thrust", p->thrust);
  } else if (const auto* l = std::get_if<LinearLaw>(&m.law)) {
    c.positive(lp + ".linear.k_t_n_per_mm2", l->k_t_n_per_mm2);
    c.non_negative(lp + ".linear.k_n_n_per_mm2", l->k_n_n_per_mm2);
    c.non_negative(lp + ".linear.k_a_n_per_mm2", l->k_a_n_per_mm2);
  }
  const auto check_modes = [&](const std::vector<Mode>& modes, const char* name) {
    for (std::size_t i = 0; i < modes.size(); ++i) {
      const std::string mp = prefix + ".structure." + name + "[" + std::to_string(i) + "]";
      c.positive(mp + ".natural_frequency_rad_s", modes[i].natural_frequency_rad_s);
      c.open_range(mp + ".damping_ratio", modes[i].damping_ratio, 0, 1);
      c.positive(mp + ".stiffness_n_per_mm", modes[i].stiffness_n_per_mm);
    }
  };
  check_modes(m.structure.tool_x, "tool_x");
  check_modes(m.structure.tool_y, "tool_y");
  check_modes(m.structure.part_x, "part_x");
  check_modes(m.structure.part_y, "part_y");
  if (mode_count(m.structure) == 0) {
    c.fail(prefix + ".structure",
           "has no modes: give at least one in tool_x, tool_y, part_x or part_y");
  }
  if (!(std::isfinite(m.internal_step_s) && m.internal_step_s >= kMinInternalStepS &&
        m.internal_step_s <= kMaxInternalStepS)) {
    c.fail(prefix + ".internal_step_s", "must be in [1e-7, 1e-4] s (0 in a document: 1e-5)",
           m.internal_step_s);
  }
  if (m.reference_cut) {
    const std::string rp = prefix + ".reference_cut";
    c.non_negative(rp + ".depth_mm", m.reference_cut->depth_mm);
    c.non_negative(rp + ".feedrate_mm_s", m.reference_cut->feedrate_mm_s);
    c.positive(rp + ".spindle_rpm", m.reference_cut->spindle_rpm);
  }
  return errors;
}

void validate(const MillingModel& model, const std::string& prefix) {
  auto errors = validation_errors(model, prefix);
  if (!errors.empty()) throw ModelError(std::move(errors));
}

void validate(const CutConditions& cut) {
  std::vector<std::string> errors;
  Checker c(errors);
  c.positive("cut.spindle_rpm", cut.spindle_rpm);
  c.non_negative("cut.feed_per_tooth_mm", cut.feed_per_tooth_mm);
  c.non_negative("cut.depth_mm", cut.depth_mm);
  if (!errors.empty()) throw std::invalid_argument(join_lines(errors));
}

std::size_t mode_count(const Structure& s) noexcept {
  return s.tool_x.size() + s.tool_y.size() + s.part_x.size() + s.part_y.size();
}

}  // namespace smc::machining
