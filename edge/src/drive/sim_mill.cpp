#include "smc/edge/sim_mill.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "smc/edge/parameters.hpp"
#include "smc/machining/anti_alias.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/simulator.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

void use_plant_model(smc::config::MillingModel& configured, smc::config::MillingModel plant) {
  if (configured.has_cutter()) *plant.mutable_cutter() = configured.cutter();
  if (configured.has_workpiece()) *plant.mutable_workpiece() = configured.workpiece();
  configured = std::move(plant);
}

void check_wideband_channel_agrees(const smc::config::SupervisorConfig& cfg) {
  const auto expects = supervision::wideband_samples_e_takes(cfg);
  const auto brings = std::max(1U, cfg.simulation().f_y_wide_samples_per_tick());
  if (expects == 0 || expects == brings) return;
  throw ConfigError(
      "operation.wideband_samples_per_tick: module E expects " + std::to_string(expects) +
      " wideband samples a period, but the simulated mill gives " + std::to_string(brings) +
      " (simulation.f_y_wide_samples_per_tick), and E would hold the feed at the "
      "first sample in contact; fix: make the two equal, with the channel's "
      "filter too (a machine's catalog record, wideband, sets them together)");
}

namespace {

using LowPass = machining::AntiAliasLowPass;

// The seed of the wideband F_y channel's noise: derived from the run's, and
// different from it.
constexpr std::uint64_t wide_seed(std::uint64_t seed) noexcept {
  return seed ^ 0x9e3779b97f4a7c15ULL;
}

enum class Phase { kCutting, kRepositioning, kDone };

}  // namespace

struct SimulatedMill::Impl {
  machining::MillingModel model;
  machining::MillSimulator sim;
  smc::config::SimulatedMill options;
  // The force of each internal step of the last sample, for the filters.
  std::vector<double> trace_x, trace_y, trace_z, trace_v;
  LowPass lp_x, lp_y, lp_z;
  LowPass lp_y_wide;  // F_y through the F_z channel's filter (ForceSample::f_y_wide_n)
  std::mt19937_64 rng;
  std::normal_distribution<double> noise{0.0, 1.0};
  // The wideband channel's noise has its own stream and its own distribution
  // (a normal distribution keeps the second value of each pair it draws), so
  // that adding the channel left the other channels' noise, and every study
  // before it, as they were.
  std::mt19937_64 rng_wide;
  std::normal_distribution<double> noise_wide{0.0, 1.0};
  // The wideband channel's filter output is sampled every `wide_stride`
  // internal steps (all of a period's: once, with the loop).
  std::size_t wide_stride = 0;
  // Depth already removed by earlier passes, per bin along the part (mm).
  std::vector<double> removed;
  double bin_mm = 0.25;
  // Engagement: tooth-tip angles on the leading half that lie over the part's band.
  std::vector<double> band_cos;
  FixedProgram program;
  int pass = 0;
  Phase phase = Phase::kDone;
  double reposition_left_s = 0;
  double axis_feed_mm_s = 0;  // the feed axis's speed (after the drive's lag)
  double lag_gain = 1;        // 1 - exp(-dt / lag) per sample; 1 = no lag
  double time_s = 0;
  double start_x = 0;
  // Tool condition: breaks in time order, the cutter's own runout, wear.
  struct Break {
    int tooth = 0;  // 0-based
    double at_s = 0, loss_mm = 1;
  };
  std::vector<Break> breaks;
  std::size_t next_break = 0;
  std::vector<double> runout_mm;  // as built
  double wear_per_mm = 0;
  double cut_length_mm = 0;
  double worn_at_mm = 0;  // cut length at the last wear update
  // Spindle: the speed it turns at, approaching the pass's at a fixed rate.
  double rpm_now = 0;
  double rpm_step = 0;     // rpm per sample period
  bool retracted = false;  // lifted clear of the part (after a breakage)

  Impl(machining::MillingModel m, const smc::config::SimulatedMill& o, double period_s)
      : model(std::move(m)),
        sim(model, sim_options(model, o, period_s)),
        options(o),
        rng(o.seed()),
        rng_wide(wide_seed(o.seed())) {}

  static machining::SimulatorOptions sim_options(const machining::MillingModel& m,
                                                 const smc::config::SimulatedMill& o,
                                                 double period_s) {
    // One call per sample, a whole number of internal steps (no coarser than
    // the model's) per call; the sensor filters run over the force of every
    // internal step (StepForceTrace), so they see the continuous force.
    const double h = m.internal_step_s;
    const double n = std::max(1.0, std::ceil(period_s / h - 1e-9));
    machining::SimulatorOptions so;
    so.sample_period_s = period_s;
    so.max_internal_step_s = period_s / n;
    so.min_spindle_rpm = o.min_spindle_rpm() > 0 ? o.min_spindle_rpm() : 100;
    // The filters take the force of each internal step, not one more
    // evaluation at the sample instant.
    so.forces_at_sample_instant = false;
    so.regenerative = !o.no_regeneration();
    return so;
  }

  double length() const noexcept { return model.workpiece.length_mm; }
  double radius() const noexcept { return model.cutter.radius_mm; }

  double removed_at(double x) const noexcept {
    if (x < 0 || x > length()) return 1e9;  // no material outside the part
    const auto i = static_cast<size_t>(std::min<double>(x / bin_mm, double(removed.size() - 1)));
    return removed[i];
  }

  // The material the current pass swept (everything behind its leading
  // edge) now stands at the pass's target depth.
  void commit(double tool_x) noexcept {
    const double target = program.depth_before(pass + 1);
    const double edge = std::min(length(), tool_x + radius());
    for (size_t i = 0; i < removed.size(); ++i) {
      if (static_cast<double>(i) * bin_mm <= edge) removed[i] = std::max(removed[i], target);
    }
  }

  void begin_reposition(double from_x) noexcept {
    phase = Phase::kRepositioning;
    axis_feed_mm_s = 0;  // the next pass starts from rest
    const double rapid = options.rapid_feedrate_mm_s() > 0 ? options.rapid_feedrate_mm_s() : 36;
    reposition_left_s = std::fabs(from_x - start_x) / rapid;
  }
};

SimulatedMill::SimulatedMill(const smc::config::MillingModel& model,
                             const smc::config::SimulatedMill& sim, double sample_period_s)
    : period_s_(sample_period_s) {
  machining::MillingModel m;
  try {
    m = machining::from_proto(model, "milling_model");
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }
  if (!(sample_period_s > 0)) throw ConfigError("sample_period_s: must be > 0");
  for (double hz : {sim.f_y_cutoff_hz(), sim.f_z_cutoff_hz(), sim.f_y_wide_cutoff_hz()}) {
    if (!(hz >= 0) || !std::isfinite(hz)) {
      throw ConfigError(
          "simulation: anti-alias cut-off frequencies (f_y_cutoff_hz, f_z_cutoff_hz, "
          "f_y_wide_cutoff_hz) must be finite and >= 0; fix: e.g. 250, 1000, 500");
    }
  }
  if (!(sim.noise_rms_n() >= 0) || !std::isfinite(sim.noise_rms_n())) {
    throw ConfigError("simulation.noise_rms_n: must be finite and >= 0; fix: e.g. 2");
  }
  if (sim.has_f_y_wide_noise_rms_n() &&
      (!(sim.f_y_wide_noise_rms_n() >= 0) || !std::isfinite(sim.f_y_wide_noise_rms_n()))) {
    throw ConfigError(
        "simulation.f_y_wide_noise_rms_n: must be finite and >= 0; fix: leave it out for "
        "noise_rms_n's, or give the channel's own, e.g. 2");
  }
  if (const auto order = sim.f_y_wide_order(); !machining::AntiAliasLowPass::is_order(order)) {
    throw ConfigError("simulation.f_y_wide_order: must be even, 2-8 (got " + std::to_string(order) +
                      "); fix: 0 or 2 for the shipped channel, e.g. 8");
  }
  const double lag = sim.feed_drive_lag_s();
  if (!(lag >= 0 && lag <= 1)) {
    throw ConfigError("simulation.feed_drive_lag_s: must be in [0, 1] s (got " +
                      std::to_string(lag) + "); fix: 0 for none, e.g. 0.02");
  }
  impl_ = std::make_unique<Impl>(std::move(m), sim, sample_period_s);
  Impl& s = *impl_;
  s.lag_gain = lag > 0 ? 1.0 - std::exp(-sample_period_s / lag) : 1.0;
  const double accel = sim.spindle_accel_rpm_s() == 0 ? 2000.0 : sim.spindle_accel_rpm_s();
  if (!(accel > 0) || !std::isfinite(accel)) {
    throw ConfigError("simulation.spindle_accel_rpm_s: must be > 0 (got " + std::to_string(accel) +
                      "); fix: 0 for the default 2000 rpm/s");
  }
  s.rpm_step = accel * sample_period_s;
  const auto steps = static_cast<std::size_t>(s.sim.steps_per_sample());
  const auto per_tick = sim.f_y_wide_samples_per_tick() == 0 ? 1U : sim.f_y_wide_samples_per_tick();
  if (per_tick > static_cast<unsigned>(ForceSample::kMaxWideSamples) || steps % per_tick != 0) {
    throw ConfigError("simulation.f_y_wide_samples_per_tick: " + std::to_string(per_tick) +
                      " samples do not divide the simulator's " + std::to_string(steps) +
                      " internal steps per sample period evenly (at most " +
                      std::to_string(ForceSample::kMaxWideSamples) +
                      "); fix: 0 or 1 for one a period, or a divisor such as 2 or 5");
  }
  s.wide_stride = steps / per_tick;
  s.trace_x.assign(steps, 0.0);
  s.trace_y.assign(steps, 0.0);
  s.trace_z.assign(steps, 0.0);
  // The vibration is kept at each step only where the channel samples
  // faster than the loop (it costs a read of the structure per step).
  if (per_tick > 1) s.trace_v.assign(steps, 0.0);
  const double rate = 1.0 / s.sim.internal_step_s();
  // A cut-off of 0 (or above Nyquist) means no filter on that channel.
  s.lp_x.configure(sim.f_y_cutoff_hz(), rate);
  s.lp_y.configure(sim.f_y_cutoff_hz(), rate);
  s.lp_z.configure(sim.f_z_cutoff_hz(), rate);
  s.lp_y_wide.configure(
      sim.f_y_wide_cutoff_hz() > 0 ? sim.f_y_wide_cutoff_hz() : sim.f_z_cutoff_hz(), rate,
      sim.f_y_wide_order() > 0 ? static_cast<int>(sim.f_y_wide_order()) : 2);
  s.removed.assign(static_cast<size_t>(std::ceil(s.length() / s.bin_mm)) + 1, 0.0);
  const auto& w = s.model.workpiece;
  const double y_lo = w.offset_mm - w.width_mm / 2, y_hi = w.offset_mm + w.width_mm / 2;
  for (int k = 0; k < 181; ++k) {
    const double th = -std::numbers::pi / 2 + std::numbers::pi * k / 180.0;
    const double y = s.radius() * std::sin(th);
    if (y >= y_lo && y <= y_hi) s.band_cos.push_back(std::cos(th));
  }
  s.start_x = -s.radius() - (sim.approach_mm() > 0 ? sim.approach_mm() : 5.0);
  const int teeth = s.model.cutter.teeth;
  for (int i = 0; i < teeth; ++i) s.runout_mm.push_back(s.sim.tooth_runout_mm(i));
  for (int k = 0; k < sim.tooth_breaks_size(); ++k) {
    const auto& b = sim.tooth_breaks(k);
    const std::string f = "simulation.tooth_breaks[" + std::to_string(k) + "]";
    if (b.tooth() < 1 || static_cast<int>(b.tooth()) > teeth) {
      throw ConfigError(f + ".tooth: " + std::to_string(b.tooth()) + " is not a tooth of the " +
                        std::to_string(teeth) + "-tooth cutter (1-based)");
    }
    if (!(b.at_s() >= 0) || !(b.edge_loss_mm() >= 0) || !std::isfinite(b.edge_loss_mm())) {
      throw ConfigError(f +
                        ": at_s and edge_loss_mm must be >= 0 (edge_loss_mm 0: the edge is "
                        "lost, 1 mm)");
    }
    s.breaks.push_back(
        {static_cast<int>(b.tooth()) - 1, b.at_s(), b.edge_loss_mm() > 0 ? b.edge_loss_mm() : 1.0});
  }
  std::stable_sort(s.breaks.begin(), s.breaks.end(),
                   [](const Impl::Break& a, const Impl::Break& b) { return a.at_s < b.at_s; });
  if (!(sim.wear_per_m() >= 0) || !std::isfinite(sim.wear_per_m())) {
    throw ConfigError("simulation.wear_per_m: must be >= 0 (0: no wear)");
  }
  s.wear_per_mm = sim.wear_per_m() / 1000.0;
}

SimulatedMill::~SimulatedMill() = default;

double SimulatedMill::part_length_mm() const noexcept { return impl_->length(); }

double SimulatedMill::remaining_depth_at(double x_mm) const noexcept {
  return impl_->program.total_depth_mm() - impl_->removed_at(x_mm);
}

void SimulatedMill::load(const FixedProgram& program) {
  Impl& s = *impl_;
  s.program = program;
  s.pass = 0;
  s.sim.reset();
  s.sim.set_tool_position(s.start_x);
  std::fill(s.removed.begin(), s.removed.end(), 0.0);
  s.lp_x.reset();
  s.lp_y.reset();
  s.lp_z.reset();
  s.lp_y_wide.reset();
  s.rng.seed(s.options.seed());
  s.rng_wide.seed(wide_seed(s.options.seed()));
  s.time_s = 0;
  // A run starts with the cutter as built.
  for (int i = 0; i < static_cast<int>(s.runout_mm.size()); ++i) {
    s.sim.set_tooth_runout_mm(i, s.runout_mm[static_cast<std::size_t>(i)]);
  }
  s.sim.set_force_scale(1.0);
  s.next_break = 0;
  s.cut_length_mm = 0;
  s.worn_at_mm = 0;
  s.phase = program.count > 0 ? Phase::kCutting : Phase::kDone;
  // The spindle is at the first pass's speed when the program starts.
  s.rpm_now = program.count > 0 ? program.passes[0].spindle_rpm : 0.0;
  s.retracted = false;
}

Status SimulatedMill::retract() noexcept {
  impl_->retracted = true;
  return Status::kOk;
}

Status SimulatedMill::change_spindle_speed(double rpm) noexcept {
  Impl& s = *impl_;
  if (!(rpm > 0) || !std::isfinite(rpm)) return Status::kError;
  for (int i = std::max(0, s.pass); i < s.program.count; ++i) {
    s.program.passes[static_cast<size_t>(i)].spindle_rpm = rpm;
  }
  return Status::kOk;
}

Status SimulatedMill::rewrite(const FixedProgram& program, int from) noexcept {
  Impl& s = *impl_;
  if (from < 0 || from >= program.count) return Status::kError;
  if (s.phase == Phase::kCutting) s.commit(s.sim.tool_position_mm());
  const double x = s.sim.tool_position_mm();
  s.program = program;
  s.pass = from;
  s.begin_reposition(x);
  return Status::kOk;
}

Status SimulatedMill::step(double feedrate_cmd_mm_s, DriveSample& out) noexcept {
  Impl& s = *impl_;
  const int pass = std::min(s.pass, std::max(0, s.program.count - 1));
  const PassSpec& spec = s.program.passes[static_cast<size_t>(pass)];
  machining::SampleInput in;
  s.rpm_now += std::clamp(spec.spindle_rpm - s.rpm_now, -s.rpm_step, s.rpm_step);
  in.spindle_rpm = s.rpm_now;
  const double target = s.program.depth_before(pass + 1);
  if (s.phase == Phase::kCutting) {
    s.axis_feed_mm_s += s.lag_gain * (std::max(0.0, feedrate_cmd_mm_s) - s.axis_feed_mm_s);
    in.feedrate_mm_s = s.lag_gain == 1.0 ? std::max(0.0, feedrate_cmd_mm_s) : s.axis_feed_mm_s;
    // The chip depth where the leading edge meets material left by earlier passes.
    const double edge = std::min(s.length(), s.sim.tool_position_mm() + s.radius());
    in.depth_mm = s.retracted ? 0.0 : std::max(0.0, target - s.removed_at(std::max(0.0, edge)));
  }
  // The tool's condition at this sample: breaks due, wear by the length cut.
  while (s.next_break < s.breaks.size() && s.breaks[s.next_break].at_s <= s.time_s) {
    const auto& b = s.breaks[s.next_break++];
    s.sim.set_tooth_runout_mm(b.tooth, s.sim.tooth_runout_mm(b.tooth) - b.loss_mm);
  }
  // (Once a millimetre of cut: each new scale recomputes the cut's pressures.)
  if (s.wear_per_mm > 0 && s.cut_length_mm - s.worn_at_mm >= 1.0) {
    s.worn_at_mm = s.cut_length_mm;
    s.sim.set_force_scale(1.0 + s.wear_per_mm * s.cut_length_mm);
  }
  machining::Sample smp;
  uint32_t status = 0;
  double fx = 0, fy = 0, fz = 0, fy_wide = 0;
  status |= s.sim.step(in, smp,
                       {s.trace_x.data(), s.trace_y.data(), s.trace_z.data(),
                        s.trace_v.empty() ? nullptr : s.trace_v.data()});
  // The wideband channel's samples of this period, at the end of each
  // stride (one stride, the whole period, when it samples with the loop).
  double wide[ForceSample::kMaxWideSamples] = {};
  double vib[ForceSample::kMaxWideSamples] = {};
  int wide_n = 0;
  for (std::size_t k = 0; k < s.trace_x.size(); ++k) {
    fx = s.lp_x(s.trace_x[k]);
    fy = s.lp_y(s.trace_y[k]);
    fz = s.lp_z(s.trace_z[k]);
    fy_wide = s.lp_y_wide(s.trace_y[k]);
    if ((k + 1) % s.wide_stride == 0) {
      if (!s.trace_v.empty()) vib[wide_n] = s.trace_v[k];
      wide[wide_n++] = fy_wide;
    }
  }
  s.time_s += period_s_;
  if (smp.teeth_in_cut > 0) s.cut_length_mm += in.feedrate_mm_s * period_s_;
  const double sigma = s.options.noise_rms_n();
  if (sigma > 0) {
    fx += sigma * s.noise(s.rng);
    fy += sigma * s.noise(s.rng);
    fz += sigma * s.noise(s.rng);
  }
  const double sigma_wide =
      s.options.has_f_y_wide_noise_rms_n() ? s.options.f_y_wide_noise_rms_n() : sigma;
  if (sigma_wide > 0) {
    for (int i = 0; i < wide_n; ++i) wide[i] += sigma_wide * s.noise_wide(s.rng_wide);
  }
  const double x = s.sim.tool_position_mm();
  out.force = ForceSample{s.time_s, fx, fy, fz, wide[wide_n - 1]};
  if (wide_n > 1) {
    out.force.wide_count = wide_n;
    std::copy(wide, wide + wide_n, out.force.f_y_wide_sub_n);
  }
  out.spindle_rpm = s.rpm_now;
  out.depth_mm = spec.depth_mm;
  out.programmed_feedrate_mm_s = spec.feedrate_mm_s;
  out.feedrate_mm_s = in.feedrate_mm_s;
  out.x_mm = x;
  out.spindle_power_w = smp.power_w;
  out.vibration_y_mm = smp.tool_y_mm - smp.part_y_mm;
  out.vibration_count = 0;
  if (wide_n > 1) {
    out.vibration_count = wide_n;
    std::copy(vib, vib + wide_n - 1, out.vibration_y_sub_mm);
    out.vibration_y_sub_mm[wide_n - 1] = out.vibration_y_mm;
  }
  out.pass_index = pass;
  out.in_pass = s.phase == Phase::kCutting;
  out.program_done = s.phase == Phase::kDone;
  // Engagement: the share of the band's leading arc over the part.
  int in_cut = 0;
  if (in.depth_mm > 0) {
    for (double c : s.band_cos) {
      const double tip = x + s.radius() * c;
      if (tip >= 0 && tip <= s.length()) ++in_cut;
    }
  }
  out.engagement = s.band_cos.empty()
                       ? 0.0
                       : static_cast<double>(in_cut) / static_cast<double>(s.band_cos.size());

  // Pass sequencing.
  if (s.phase == Phase::kCutting && x - s.radius() > s.length()) {
    s.commit(x);
    if (s.pass + 1 < s.program.count) {
      ++s.pass;
      s.begin_reposition(x);
    } else {
      s.phase = Phase::kDone;
    }
  } else if (s.phase == Phase::kRepositioning) {
    s.reposition_left_s -= period_s_;
    if (s.reposition_left_s <= 0) {
      s.sim.set_tool_position(s.start_x);
      s.phase = Phase::kCutting;
    }
  }
  const bool bad =
      (status & (machining::StepStatus::kInvalidInput | machining::StepStatus::kNotFinite)) != 0;
  return bad ? Status::kError : Status::kOk;
}

}  // namespace smc::edge
