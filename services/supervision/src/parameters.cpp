#include "smc/supervision/parameters.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>

#include "smc_config.pb.h"

namespace smc::supervision {

double cutting_speed_m_s(double cutter_radius_mm, double spindle_rpm) noexcept {
  return 2.0 * std::numbers::pi * cutter_radius_mm * 1e-3 * spindle_rpm / 60.0;
}

double force_reference_n(double max_power_w, double cutter_radius_mm, double spindle_rpm,
                         double safety_factor) noexcept {
  const double v_m_s = cutting_speed_m_s(cutter_radius_mm, spindle_rpm);
  if (!(v_m_s > 0)) return 0;
  return max_power_w / v_m_s / (safety_factor > 0 ? safety_factor : 1.0);
}

double feedrate_mm_s(double feed_per_tooth_mm, int teeth, double spindle_rpm) noexcept {
  return feed_per_tooth_mm * teeth * spindle_rpm / 60.0;
}

double feed_per_tooth_mm(double feedrate_mm_s, int teeth, double spindle_rpm) noexcept {
  const double teeth_per_s = teeth * spindle_rpm / 60.0;
  return teeth_per_s > 0 ? feedrate_mm_s / teeth_per_s : 0.0;
}

double Parameters::force_reference_at(double spindle_rpm) const noexcept {
  if (force_reference_n > 0) return force_reference_n;
  return supervision::force_reference_n(max_spindle_power_w, cutter_radius_mm, spindle_rpm,
                                        force_safety_factor);
}

double Parameters::feedrate_for(double feed_per_tooth_mm, double spindle_rpm) const noexcept {
  return feedrate_mm_s(feed_per_tooth_mm, teeth, spindle_rpm);
}

double Parameters::feed_per_tooth_for(double feedrate_mm_s, double spindle_rpm) const noexcept {
  return feed_per_tooth_mm(feedrate_mm_s, teeth, spindle_rpm);
}

namespace {

// Records a problem and goes on, so one pass reports every bad field. A
// bound that is itself bad (NaN after an earlier problem) skips the check:
// its own problem is already on the list.
class Checker {
 public:
  Checker(std::string prefix, common::Diagnostics& problems)
      : prefix_(std::move(prefix)), problems_(problems) {}

  double positive(const char* field, double v, const char* fix) const {
    if (!(v > 0) || !std::isfinite(v)) fail(field, "must be > 0", v, fix);
    return v;
  }
  double non_negative(const char* field, double v, const char* fix) const {
    if (!(v >= 0) || !std::isfinite(v)) fail(field, "must be >= 0", v, fix);
    return v;
  }
  double in_range(const char* field, double v, double lo, double hi, const char* fix) const {
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return v;
    if (!(v >= lo && v <= hi)) {
      std::ostringstream why;
      why << "must be in [" << lo << ", " << hi << "]";
      fail(field, why.str(), v, fix);
    }
    return v;
  }
  void fail(const char* field, const std::string& why, double v, const char* fix) const {
    problems_.add(prefix_ + field, why + " (got " + common::number(v) + ")", fix);
  }

 private:
  std::string prefix_;
  common::Diagnostics& problems_;
};

}  // namespace

Parameters read_parameters(const smc::config::SupervisorConfig& cfg,
                           common::Diagnostics& problems) {
  Parameters p;
  const Checker m("supervisor_config.machine.", problems);
  const auto& mc = cfg.machine();
  p.max_spindle_power_w = m.positive("max_spindle_power_w", mc.max_spindle_power_w(),
                                     "set the spindle's rated power, e.g. 745.7");
  p.max_feedrate_mm_s = m.positive("max_feedrate_mm_s", mc.max_feedrate_mm_s(),
                                   "set the axes' maximum feedrate, e.g. 36");
  p.max_spindle_rpm = m.positive("max_spindle_rpm", mc.max_spindle_rpm(),
                                 "set the spindle's maximum speed, e.g. 3000");
  p.min_spindle_rpm =
      mc.min_spindle_rpm() == 0
          ? p.max_spindle_rpm / 4
          : m.in_range(
                "min_spindle_rpm", mc.min_spindle_rpm(), 1.0, p.max_spindle_rpm,
                "set the lowest supervised spindle speed, e.g. 750 (0: max_spindle_rpm / 4)");

  const Checker o("supervisor_config.operation.", problems);
  const auto& op = cfg.operation();
  p.max_feed_per_tooth_mm = o.positive("max_feed_per_tooth_mm", op.max_feed_per_tooth_mm(),
                                       "set the handbook limit, e.g. 0.6");
  p.min_feed_per_tooth_mm =
      o.in_range("min_feed_per_tooth_mm", op.min_feed_per_tooth_mm(), 1e-6, p.max_feed_per_tooth_mm,
                 "set the lowest controlled feed, e.g. 0.005");
  // Counts: checked, then clamped before the conversion (an int cannot hold
  // every uint32 a document may carry).
  p.teeth = static_cast<int>(
      std::clamp(o.in_range("teeth", op.teeth(), 1, 64, "set the cutter's teeth"), 0.0, 64.0));
  p.cutter_radius_mm =
      o.positive("cutter_radius_mm", op.cutter_radius_mm(), "set the cutter radius, e.g. 25");
  p.sample_period_s = o.in_range("sample_period_s", op.sample_period_s(), 1e-5, 0.01,
                                 "set the force sampling period, e.g. 0.0005");
  const bool sample_ok = p.sample_period_s >= 1e-5 && p.sample_period_s <= 0.01;
  const double sample_bound = sample_ok ? p.sample_period_s : std::nan("");
  p.fast_period_s = o.in_range("fast_period_s", op.fast_period_s(), sample_bound, 1.0,
                               "set modules A and B's period, e.g. 0.01");
  p.slow_period_s = o.in_range("slow_period_s", op.slow_period_s(), sample_bound, 2.0,
                               "set one spindle revolution, e.g. 0.04 at 1500 rpm");
  p.contact_threshold_n = o.positive("contact_threshold_n", op.contact_threshold_n(),
                                     "set the contact threshold on F_Y, e.g. 50");
  p.force_reference_n = o.non_negative("force_reference_n", op.force_reference_n(),
                                       "use 0 to derive it from the power limit");
  p.force_safety_factor = op.force_safety_factor() == 0
                              ? 1.0
                              : o.in_range("force_safety_factor", op.force_safety_factor(), 1.0,
                                           10.0, "use 1 for no margin");
  p.model_time_constant_s = o.positive("model_time_constant_s", op.model_time_constant_s(),
                                       "set module L's closed-loop time constant, e.g. 0.1");
  p.adaptive_time_constant_s = o.positive("adaptive_time_constant_s", op.adaptive_time_constant_s(),
                                          "set module K's closed-loop time constant, e.g. 0.15");
  p.rls_forgetting = o.in_range("rls_forgetting", op.rls_forgetting(), 0.5, 1.0,
                                "set module H's forgetting factor, e.g. 0.95");
  p.adaptive_feed_exponent = o.in_range("adaptive_feed_exponent", op.adaptive_feed_exponent(), 0.05,
                                        1.5, "set the feed exponent alpha, e.g. 0.63");
  p.chatter_threshold = o.in_range("chatter_threshold", op.chatter_threshold(), 1e-3, 1.0,
                                   "set module E's energy-ratio threshold, e.g. 0.3");
  p.chatter_confirm_revolutions = static_cast<int>(
      std::clamp(o.in_range("chatter_confirm_revolutions", op.chatter_confirm_revolutions(), 1, 50,
                            "set how many revolutions must exceed the threshold, e.g. 2"),
                 0.0, 50.0));
  p.chatter_band_low_hz = o.non_negative("chatter_band_low_hz", op.chatter_band_low_hz(),
                                         "set the chatter search band, e.g. 150");
  p.chatter_band_high_hz =
      o.in_range("chatter_band_high_hz", op.chatter_band_high_hz(), p.chatter_band_low_hz,
                 0.5 / sample_bound, "keep the band below the Nyquist frequency");
  p.harmonic_guard_hz = o.non_negative("harmonic_guard_hz", op.harmonic_guard_hz(),
                                       "set the band ignored around tooth harmonics, e.g. 15");
  p.chatter_min_rms_n = o.non_negative("chatter_min_rms_n", op.chatter_min_rms_n(),
                                       "set the F_z RMS below which E decides nothing, e.g. 5");
  p.suppression_hold_s = o.in_range("suppression_hold_s", op.suppression_hold_s(), 0, 60,
                                    "set module G's feed hold, e.g. 0.2");
  p.power_time_constant_s =
      op.power_time_constant_s() == 0
          ? 0.1
          : o.in_range("power_time_constant_s", op.power_time_constant_s(), 0.001, 10.0,
                       "set module M's ratio filter time constant, e.g. 0.1 (0: the default)");
  p.power_target_fraction =
      op.power_target_fraction() == 0
          ? 0.95
          : o.in_range("power_target_fraction", op.power_target_fraction(), 0.5, 1.0,
                       "set the share of P_max module M holds, e.g. 0.95 (0: the default)");
  // Modules beyond the paper; 0 takes the default.
  auto or_default = [&](const char* field, double v, double dflt, double lo, double hi,
                        const char* fix) {
    return v == 0 ? dflt : o.in_range(field, v, lo, hi, fix);
  };
  p.breakage_threshold = or_default("breakage_threshold", op.breakage_threshold(), 0.3, 0.05, 2.0,
                                    "set module N's drop-and-rise share, e.g. 0.3 (0: default)");
  p.speed_change_frequency_margin =
      or_default("speed_change_frequency_margin", op.speed_change_frequency_margin(), 0.04, 1e-6,
                 0.3, "set module O's margin below the chatter frequency, e.g. 0.04 (0: default)");
  p.speed_change_max_ratio =
      or_default("speed_change_max_ratio", op.speed_change_max_ratio(), 2.0, 1.0, 10.0,
                 "set how far module O may move the speed, e.g. 2 (0: default)");
  p.spindle_at_speed_tolerance =
      or_default("spindle_at_speed_tolerance", op.spindle_at_speed_tolerance(), 0.01, 1e-4, 0.2,
                 "set the at-speed band, e.g. 0.01 (0: default)");
  p.speed_change_timeout_s =
      or_default("speed_change_timeout_s", op.speed_change_timeout_s(), 5.0, 0.01, 60.0,
                 "set the time the spindle has to reach a new speed, e.g. 5 (0: default)");
  p.vibration_sensor_cutoff_hz =
      or_default("wideband_cutoff_hz", op.wideband_cutoff_hz(), 1000.0, 1.0, 1e6,
                 "set the wideband F_y channel's anti-alias cut-off, e.g. 500 (0: 1000 Hz)");
  if (const auto order = op.wideband_filter_order(); order == 0) {
    p.vibration_sensor_order = 2;
  } else if (order % 2 != 0 || order > 8) {
    o.fail("wideband_filter_order", "must be even, 2-8", order,
           "give the wideband channel's Butterworth order, e.g. 2 (0: 2)");
  } else {
    p.vibration_sensor_order = static_cast<int>(order);
  }
  p.vibration_sensor_noise_rms_n =
      or_default("wideband_noise_rms_n", op.wideband_noise_rms_n(), 0.0, 0.0, 1000.0,
                 "set the wideband F_y channel's noise in N rms, e.g. 2 (0: none taken out)");
  if (const auto per_tick = op.wideband_samples_per_tick(); per_tick == 0) {
    p.vibration_samples_per_tick = 1;
  } else if (per_tick > static_cast<uint32_t>(Parameters::kMaxVibrationSamplesPerTick)) {
    o.fail("wideband_samples_per_tick", "must be 1-8", per_tick,
           "give the wideband channel's samples per sample period, e.g. 5 (0: 1)");
  } else {
    p.vibration_samples_per_tick = static_cast<int>(per_tick);
  }
  if (op.identification_levels_size() > Parameters::kMaxIdentificationLevels) {
    o.fail("identification_levels", "has more levels than the edge holds",
           op.identification_levels_size(), "give at most 4 levels, e.g. [0.6, 0.8]");
  } else {
    for (int i = 0; i < op.identification_levels_size(); ++i) {
      const std::string field = "identification_levels[" + std::to_string(i) + "]";
      p.identification_levels[i] =
          o.in_range(field.c_str(), op.identification_levels(i), 0.3, 1.0,
                     "give F_ref multipliers inside the power limit, e.g. [0.6, 0.8]");
    }
    p.identification_level_count = op.identification_levels_size();
  }
  const double ident_revs =
      o.in_range("identification_revolutions", op.identification_revolutions(), 0, 200,
                 "give the revolutions per level, e.g. 10 (0: no identification segment)");
  p.identification_revolutions = ident_revs <= 200 ? static_cast<int>(ident_revs) : 0;
  if (p.identification_revolutions > 0 && p.identification_level_count == 0) {
    o.fail("identification_revolutions", "is set but identification_levels is empty",
           op.identification_revolutions(), "give the levels too, or 0 revolutions");
  }
  p.force_sensor_range_n = o.positive("force_sensor_range_n", op.force_sensor_range_n(),
                                      "set the dynamometer's range, e.g. 5000");

  const auto& fm = cfg.force_model();
  p.has_force_model = fm.k_kn() > 0 && fm.alpha() > 0 && fm.beta() > 0;
  if (cfg.has_force_model() && !p.has_force_model) {
    const Checker f("supervisor_config.force_model.", problems);
    f.positive("k_kn", fm.k_kn(), "give K of F_Y = K d^beta f^alpha in kN, e.g. 0.76");
    f.positive("beta", fm.beta(), "give the depth exponent, e.g. 0.65");
    f.positive("alpha", fm.alpha(), "give the feed exponent, e.g. 0.63");
  }
  p.model_k_kn = fm.k_kn();
  p.model_beta = fm.beta();
  p.model_alpha = fm.alpha();

  if (cfg.has_milling_model() && p.cutter_radius_mm > 0) {
    const auto& w = cfg.milling_model().workpiece();
    const double r = p.cutter_radius_mm;
    const double lo = std::clamp((w.offset_mm() - w.width_mm() / 2) / r, -1.0, 1.0);
    const double hi = std::clamp((w.offset_mm() + w.width_mm() / 2) / r, -1.0, 1.0);
    if (w.width_mm() > 0 && std::isfinite(lo) && std::isfinite(hi) && hi > lo) {
      p.cut_arc_rad = std::asin(hi) - std::asin(lo);
    }
  }
  if (cfg.has_milling_model()) {
    const auto& st = cfg.milling_model().structure();
    const std::pair<const char*, const google::protobuf::RepeatedPtrField<config::Mode>*> y[] = {
        {"tool_y", &st.tool_y()}, {"part_y", &st.part_y()}};
    for (const auto& [name, modes] : y) {
      for (int i = 0; i < modes->size(); ++i) {
        const auto& mode = modes->Get(i);
        const Checker c("supervisor_config.milling_model.structure." + std::string(name) + "[" +
                            std::to_string(i) + "].",
                        problems);
        const double w = c.positive("natural_frequency_rad_s", mode.natural_frequency_rad_s(),
                                    "give the mode's natural frequency, e.g. 4100");
        const double zeta = c.in_range("damping_ratio", mode.damping_ratio(), 1e-9, 1 - 1e-9,
                                       "give the mode's damping ratio, e.g. 0.11");
        const double k = c.positive("stiffness_n_per_mm", mode.stiffness_n_per_mm(),
                                    "give the mode's stiffness, e.g. 14000");
        const bool ok = w > 0 && std::isfinite(w) && zeta >= 1e-9 && zeta <= 1 - 1e-9 && k > 0 &&
                        std::isfinite(k);
        // More than kMaxVibrationModes: E uses the first (the README says so).
        if (ok && p.vibration_mode_count < Parameters::kMaxVibrationModes) {
          p.vibration_modes[p.vibration_mode_count++] = {
              mode.natural_frequency_rad_s(), mode.damping_ratio(), mode.stiffness_n_per_mm()};
        }
      }
    }
  }

  if (!sample_ok) return p;  // the derived counts need a sample period
  set_vibration_rules_for_channel(p, vibration_channel_rate_hz(p));
  // A count of sample periods, refused past kMaxCount (a day at 2 kHz: no
  // period of the edge is near it, and an int must hold it).
  constexpr double kMaxCount = 2e8;
  auto count = [&](const Checker& mod, double n, const char* field, double v) {
    if (!(n >= 0 && n <= kMaxCount)) {
      mod.fail(field, "is longer than the edge handles (more than 2e8 sample periods)", v,
               "give a period of seconds, not more");
      return 0;
    }
    return static_cast<int>(n);
  };
  auto samples = [&](double period, const char* field) {
    if (!(period > 0) || !std::isfinite(period)) return 0;  // reported above
    const double n = period / p.sample_period_s;
    const double r = std::round(n);
    if (!(std::fabs(n - r) <= 1e-6 * n)) {
      o.fail(field, "must be a whole number of sample periods", period,
             "make it a multiple of sample_period_s");
      return 0;
    }
    return count(o, r, field, period);
  };
  p.samples_per_fast = samples(p.fast_period_s, "fast_period_s");
  p.samples_per_revolution = samples(p.slow_period_s, "slow_period_s");
  p.samples_per_hold = count(o, std::round(p.suppression_hold_s / p.sample_period_s),
                             "suppression_hold_s", p.suppression_hold_s);
  if (p.min_spindle_rpm > 0 && p.max_spindle_rpm >= p.min_spindle_rpm) {
    p.max_samples_per_revolution =
        std::max(p.samples_per_revolution,
                 count(m, std::ceil(60.0 / p.min_spindle_rpm / p.sample_period_s - 1e-9),
                       "min_spindle_rpm", p.min_spindle_rpm));
    p.min_samples_per_revolution =
        std::max(1, count(m, std::floor(60.0 / p.max_spindle_rpm / p.sample_period_s + 1e-9),
                          "max_spindle_rpm", p.max_spindle_rpm));
    if (p.max_samples_per_revolution > kMaxSamplesPerRevolution) {
      m.fail("min_spindle_rpm",
             "gives revolutions of " + std::to_string(p.max_samples_per_revolution) +
                 " samples, more than the edge handles (" +
                 std::to_string(kMaxSamplesPerRevolution) + ")",
             p.min_spindle_rpm, "raise min_spindle_rpm or lengthen sample_period_s");
    }
  }
  return p;
}

double vibration_channel_rate_hz(const Parameters& p) noexcept {
  return p.sample_period_s > 0 ? p.vibration_samples_per_tick / p.sample_period_s : 0;
}

namespace {

bool runs_chatter_detector(const smc::config::SupervisorConfig& cfg) noexcept {
  const auto& mods = cfg.modules();
  return std::find(mods.begin(), mods.end(), "E") != mods.end();
}

bool has_structure_in_y(const smc::config::SupervisorConfig& cfg) noexcept {
  const auto& st = cfg.milling_model().structure();
  return st.tool_y_size() + st.part_y_size() > 0;
}

}  // namespace

bool chatter_detector_without_structure(const smc::config::SupervisorConfig& cfg) noexcept {
  return runs_chatter_detector(cfg) && !has_structure_in_y(cfg);
}

unsigned wideband_samples_e_takes(const smc::config::SupervisorConfig& cfg) noexcept {
  return runs_chatter_detector(cfg) && has_structure_in_y(cfg)
             ? std::max(1U, cfg.operation().wideband_samples_per_tick())
             : 0U;
}

WidebandModeLoss wideband_mode_loss(const Parameters& p) noexcept {
  WidebandModeLoss worst;
  worst.nyquist_hz = vibration_channel_rate_hz(p) / 2;
  const double fc = p.vibration_sensor_cutoff_hz;
  for (int i = 0; i < p.vibration_mode_count; ++i) {
    WidebandModeLoss m;
    m.nyquist_hz = worst.nyquist_hz;
    m.mode_hz = p.vibration_modes[i].natural_frequency_rad_s / (2 * std::numbers::pi);
    m.above_nyquist = m.mode_hz >= m.nyquist_hz;
    m.loss_db = 10 * std::log10(1 + std::pow(m.mode_hz / fc, 2 * p.vibration_sensor_order));
    const bool worse =
        m.above_nyquist != worst.above_nyquist ? m.above_nyquist : m.loss_db > worst.loss_db;
    if (i == 0 || worse) worst = m;
  }
  return worst;
}

namespace {

// The sentence of wideband_channel_warning for `p`'s channel and modes.
std::string channel_warning_text(const Parameters& p) {
  const auto loss = wideband_mode_loss(p);
  std::ostringstream w;
  w << "module E's wideband channel (" << std::setprecision(3)
    << vibration_channel_rate_hz(p) / 1000 << " kHz through an order-" << p.vibration_sensor_order
    << " filter at " << std::lround(p.vibration_sensor_cutoff_hz) << " Hz) ";
  if (loss.above_nyquist) {
    w << "cannot see the structure's y mode at " << std::lround(loss.mode_hz)
      << " Hz, above its Nyquist frequency (" << std::lround(loss.nyquist_hz)
      << " Hz), so E misses chatter there; fix: a channel sampled faster than twice the "
         "mode (operation.wideband_samples_per_tick; a machine's catalog record, wideband)";
  } else if (loss.loss_db > kWidebandModeLossWarnDb) {
    w << "takes the structure's y mode at " << std::lround(loss.mode_hz) << " Hz " << std::fixed
      << std::setprecision(1) << loss.loss_db
      << " dB down, and E undoing it lifts the channel's noise as much where that mode "
         "chatters: measured, such channels catch fewer onsets in time and read noise as "
         "chatter (edge/CHATTER.md, \"What the channel's filter costs E\"); fix: a sensor "
         "filter that takes it at most "
      << std::setprecision(0) << kWidebandModeLossWarnDb
      << " dB down (a higher cut-off or a lower order), told to E in "
         "operation.wideband_cutoff_hz and wideband_filter_order (a machine's catalog record, "
         "wideband)";
  } else {
    return {};
  }
  return w.str();
}

}  // namespace

std::string wideband_channel_warning(const smc::config::SupervisorConfig& cfg) {
  if (wideband_samples_e_takes(cfg) == 0) return {};
  common::Diagnostics problems;
  const Parameters p = read_parameters(cfg, problems);
  if (!problems.empty()) return {};
  return channel_warning_text(p);
}

std::string wideband_channel_warning(double rate_hz, double cutoff_hz, int filter_order,
                                     const smc::config::Structure& structure) {
  if (!(rate_hz > 0 && cutoff_hz > 0 && filter_order > 0) || !std::isfinite(rate_hz) ||
      !std::isfinite(cutoff_hz)) {
    return {};
  }
  Parameters p;
  p.sample_period_s = 1 / rate_hz;
  p.vibration_samples_per_tick = 1;
  p.vibration_sensor_cutoff_hz = cutoff_hz;
  p.vibration_sensor_order = filter_order;
  p.vibration_mode_count = 0;
  for (const auto* modes : {&structure.tool_y(), &structure.part_y()}) {
    for (const auto& m : *modes) {
      const double w = m.natural_frequency_rad_s();
      if (!(w > 0) || !std::isfinite(w)) continue;
      if (p.vibration_mode_count < Parameters::kMaxVibrationModes) {
        p.vibration_modes[p.vibration_mode_count++] = {w, m.damping_ratio(),
                                                       m.stiffness_n_per_mm()};
      }
    }
  }
  if (p.vibration_mode_count == 0) return {};
  return channel_warning_text(p);
}

void set_vibration_rules_for_channel(Parameters& p, double channel_rate_hz) noexcept {
  const Parameters loop_rate;  // the defaults: the set chosen at 2 kHz
  // Only the rules that differ between the two sets; the others keep the
  // loop-rate values in both.
  p.chatter_vibration_rise = loop_rate.chatter_vibration_rise;
  p.chatter_vibration_pause = loop_rate.chatter_vibration_pause;
  p.chatter_vibration_climb = loop_rate.chatter_vibration_climb;
  p.chatter_vibration_growth = loop_rate.chatter_vibration_growth;
  p.chatter_vibration_flip_revolutions = loop_rate.chatter_vibration_flip_revolutions;
  p.chatter_vibration_keep_across_steps = loop_rate.chatter_vibration_keep_across_steps;
  p.chatter_vibration_held = loop_rate.chatter_vibration_held;
  // A rate a hair under 10 kHz from the division is still 10 kHz.
  if (channel_rate_hz >= kFineChannelRateHz * (1 - 1e-9)) {
    // Chosen on the detector study's grid and full runs at 10 kHz with the
    // label at the same rate, with no false detection allowed on either
    // (edge/CHATTER.md, "Label and channel at 10 kHz"). E reads q within
    // 1-3 % of the mill's there, so the rules can sit at the label's own
    // threshold (0.15) and take any growth; a period doubling must hold three
    // revolutions, as stable cuts' halfway orders reach the flip level for two.
    // The rules keep their history across a step in the mean F_z (chatter's
    // own growth steps it), save where the cutter crosses the ledge an
    // aborted pass left: there the step is the cut's, and kept they compared
    // the revolution before it with L's cut in the feed after it and read
    // it as chatter (edge/CHATTER.md, "Shipped at 10 kHz").
    p.chatter_vibration_rise = 0.15;
    p.chatter_vibration_pause = 0.155;
    p.chatter_vibration_climb = 0.15;
    p.chatter_vibration_growth = 1.0;
    p.chatter_vibration_flip_revolutions = 3;
    p.chatter_vibration_keep_across_steps = true;
    // q held at the label's threshold with the cutter wholly in the part
    // (two judged revolutions' mean above it, neither below 0.14): stable
    // cuts there stay below 0.12, while chatter that hovers just above 0.15
    // before it grows gave no other rule its pattern. At 10 kHz only: at 4
    // kHz E's q reads too far from the mill's for a level at the label's
    // own threshold (edge/CHATTER.md, "The held rule").
    if (channel_rate_hz >= kHeldRuleChannelRateHz * (1 - 1e-9)) p.chatter_vibration_held = 0.15;
  }
}

Parameters parameters_from_config(const smc::config::SupervisorConfig& cfg) {
  common::Diagnostics problems;
  Parameters p = read_parameters(cfg, problems);
  if (!problems.ok()) throw ConfigError(std::move(problems));
  return p;
}

}  // namespace smc::supervision
