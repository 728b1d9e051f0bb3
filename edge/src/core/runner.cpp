#include "smc/edge/runner.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "smc/edge/fractional_delay.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

std::vector<ScheduledInput> parse_feed_hold(const std::string& spec) {
  const auto colon = spec.find(':');
  char* end = nullptr;
  const std::string t_str = spec.substr(0, colon);
  const double t = std::strtod(t_str.c_str(), &end);
  bool ok = colon != std::string::npos && end != t_str.c_str() && *end == '\0' && t >= 0;
  double d = 0;
  if (ok) {
    const std::string d_str = spec.substr(colon + 1);
    d = std::strtod(d_str.c_str(), &end);
    ok = end != d_str.c_str() && *end == '\0' && d > 0;
  }
  if (!ok || !std::isfinite(t) || !std::isfinite(d)) {
    throw std::invalid_argument("--feed-hold-at '" + spec +
                                "': expected T:DURATION in seconds, e.g. 20:1.5");
  }
  return {{ScheduledInput::kFeedHoldOn, t}, {ScheduledInput::kFeedHoldOff, t + d}};
}

RunResult run_virtual(EdgeCore& core, const RunOptions& options) {
  RunResult run;
  std::vector<ScheduledInput> inputs = options.inputs;
  std::stable_sort(inputs.begin(), inputs.end(),
                   [](const ScheduledInput& a, const ScheduledInput& b) { return a.t_s < b.t_s; });
  size_t next_input = 0;
  OperatorInputs op;
  const double dt = core.config().params.sample_period_s;
  const auto max_ticks = static_cast<uint64_t>(std::ceil(options.max_time_s / dt));
  const int decimation = std::max(1, options.sample_decimation);
  if (options.keep_samples) {
    run.samples.reserve(static_cast<size_t>(std::min<uint64_t>(max_ticks, 4'000'000)) /
                        static_cast<size_t>(decimation));
  }
  // The vibration between samples: kept from the first sample on, if the
  // drive gives it then and every sample is kept.
  bool fine = false;
  EdgeEvent ev;
  RevolutionRecord rev;
  ForceBatchRecord batch;
  for (uint64_t i = 0; i < max_ticks; ++i) {
    const double t_next = static_cast<double>(i + 1) * dt;
    while (next_input < inputs.size() && inputs[next_input].t_s <= t_next + 1e-12) {
      switch (inputs[next_input].kind) {
        case ScheduledInput::kFeedHoldOn:
          op.feed_hold = true;
          break;
        case ScheduledInput::kFeedHoldOff:
          op.feed_hold = false;
          ++op.releases;
          break;
        case ScheduledInput::kChatterSignal:
          ++op.chatter_signals;
          break;
      }
      core.set_operator_inputs(op);
      ++next_input;
    }
    if (options.before_tick && !options.before_tick()) break;
    core.tick(false);
    if (options.on_tick) options.on_tick(core);
    if (options.keep_samples && i % static_cast<uint64_t>(decimation) == 0) {
      const DriveSample& d = core.drive_sample();
      const Signals& s = core.signals();
      run.samples.push_back(TraceSample{
          d.force.t_s, d.x_mm, d.force.f_y_n, d.force.f_z_n, d.force.f_y_wide_n, s.f_y_peak_n,
          s.force_reference_n, s.feedrate_cmd_mm_s, d.depth_mm, d.spindle_rpm, d.spindle_power_w,
          d.vibration_y_mm, d.engagement, static_cast<int16_t>(d.pass_index), d.in_pass, s.contact,
          s.active, core.situation().active_steps});
      if (i == 0 && decimation == 1 && options.keep_vibration_between_samples &&
          d.vibration_count > 1) {
        fine = true;
        run.vibration_per_sample = d.vibration_count;
      }
      if (fine) {
        if (d.vibration_count != run.vibration_per_sample) {
          throw std::runtime_error(
              "run_virtual: the drive gave " + std::to_string(d.vibration_count) +
              " vibration values between samples at t = " + std::to_string(d.force.t_s) + " s, " +
              std::to_string(run.vibration_per_sample) + " at the first");
        }
        run.vibration_sub_mm.insert(run.vibration_sub_mm.end(), d.vibration_y_sub_mm,
                                    d.vibration_y_sub_mm + d.vibration_count);
      }
    }
    while (core.events().try_pop(ev)) {
      if (ev.kind == EventKind::kToolBroken && run.tool_broken_s < 0) run.tool_broken_s = ev.t_s;
      run.events.push_back(ev);
    }
    while (core.revolutions().try_pop(rev)) run.revolutions.push_back(rev);
    while (core.batches().try_pop(batch)) {
    }
    run.ticks = i + 1;
    if (core.done()) {
      run.completed = true;
      break;
    }
    if (run.tool_broken_s >= 0 &&
        core.drive_sample().force.t_s >= run.tool_broken_s + options.after_breakage_s) {
      break;
    }
  }
  run.end_time_s = core.drive_sample().force.t_s;
  return run;
}

// Chatter onset from the simulated vibration, independent of module E. A
// stable cut repeats itself every revolution (forced vibration at the tooth
// harmonics); chatter does not. Per revolution in the cut, the statistic is
// RMS(v_k - v_{k-1}) / RMS(v_k) of the relative tool-part vibration v over
// consecutive revolutions: about 0.02-0.05 while the cutter enters the part
// (the forced vibration changes slowly), growing past 1 in chatter.
std::vector<RevolutionChange> vibration_change(const RunResult& run, double still_period_s,
                                               int teeth, const std::vector<double>* forced) {
  constexpr double kMinEngagement = 0.05;
  std::vector<RevolutionChange> out;
  if (run.samples.size() < 16) return out;
  if (forced != nullptr && forced->size() != run.samples.size()) {
    throw std::invalid_argument("vibration_change: the forced vibration has " +
                                std::to_string(forced->size()) + " samples, the run " +
                                std::to_string(run.samples.size()));
  }
  // The vibration the label reads: n values a sample (the run's vibration
  // between samples, where it has it and no forced vibration is given), m
  // counting them; sample m / n is the one whose period holds value m.
  const bool fine = forced == nullptr && run.vibration_per_sample > 1 &&
                    run.vibration_sub_mm.size() ==
                        run.samples.size() * static_cast<size_t>(run.vibration_per_sample);
  const size_t n = fine ? static_cast<size_t>(run.vibration_per_sample) : 1;
  const size_t values = run.samples.size() * n;
  auto v_at = [&](size_t m) {
    return fine ? run.vibration_sub_mm[m] : run.samples[m].vibration_y_mm;
  };
  // What the label compares from one revolution to the next: v, or the
  // vibration regeneration adds to the forced one.
  auto compared = [&](size_t m) {
    const double v = v_at(m);
    return forced != nullptr ? v - (*forced)[m] : v;
  };
  const double dt = run.samples[1].t_s - run.samples[0].t_s;
  if (!(dt > 0)) return out;
  const double dv = dt / static_cast<double>(n);  // between the values read
  // The holds that react to chatter: C's, G's, and O's while the spindle changes speed.
  const ModuleMask hold =
      static_cast<ModuleMask>(bit(ModuleId::C) | bit(ModuleId::G) | bit(ModuleId::O));
  auto period_s = [&](const TraceSample& x) {
    return x.spindle_rpm > 0 ? 60.0 / x.spindle_rpm : still_period_s;
  };
  // Revolutions of the trace, by the spindle speed it records (as the
  // core's revolution clock counts them), in samples.
  std::vector<size_t> starts{0};
  double phase = 0;
  for (size_t k = 0; k < run.samples.size(); ++k) {
    phase += dt / period_s(run.samples[k]);
    if (phase < 1.0 - 1e-9) continue;
    phase = std::max(0.0, phase - 1.0);
    if (phase < 1e-9) phase = 0;
    starts.push_back(k + 1);
  }
  const size_t revs = starts.size() - 1;
  out.resize(revs);
  // A period doubling's share of a revolution's AC energy: its vibration's
  // components at the spindle orders halfway between tooth harmonics
  // (teeth / 2, 3 teeth / 2, ... below the Nyquist frequency of the values
  // read), each read by its own Fourier sum over the revolution's values,
  // against the revolution's AC energy (Parseval: exact for a whole number
  // of values a revolution; between, orders next to a halfway one leak
  // into it, below 0.01 of the energy at 1194 rpm in
  // ChatterLabel.AVibrationThatRepeatsBetweenSamplesIsNoChange).
  const bool doubling = teeth >= 2 && teeth % 2 == 0;
  auto halfway_share = [&](size_t r) {
    const size_t first = starts[r] * n, end = starts[r + 1] * n;
    const auto count = static_cast<double>(end - first);
    double mean = 0;
    for (size_t m = first; m < end; ++m) mean += v_at(m);
    mean /= count;
    double ac = 0;
    for (size_t m = first; m < end; ++m) {
      const double v = v_at(m) - mean;
      ac += v * v;
    }
    const double spindle_hz = 1.0 / period_s(run.samples[starts[r]]);
    double halfway = 0;
    for (int order = teeth / 2; order * spindle_hz < 0.5 / dv; order += teeth) {
      // e^(-i omega t) value by value, by rotation.
      const std::complex<double> step =
          std::polar(1.0, -2 * std::numbers::pi * order * spindle_hz * dv);
      std::complex<double> turn = 1, sum = 0;
      for (size_t m = first; m < end; ++m, turn *= step) sum += (v_at(m) - mean) * turn;
      halfway += 2 * std::norm(sum) / count;
    }
    return ac > 0 ? std::min(halfway / ac, 1.0) : 0.0;
  };
  FractionalDelay delay;
  delay.set(0, FractionalDelay::kMaxHalf);
  // Per revolution: the statistic, and whether it is comparable with the
  // revolution before. The vibration one revolution earlier is read between
  // values, when a revolution is not a whole number of them, through a
  // band-limited fractional delay (as module E reads its estimate):
  // linear interpolation reads a repeating vibration near the tool mode as
  // a change of up to half of it.
  for (size_t r = 0; r < revs; ++r) {
    RevolutionChange& c = out[r];
    c.first_sample = starts[r];
    c.end_sample = starts[r + 1];
    if (r == 0) continue;
    double diff = 0, energy = 0;
    bool ok = true;
    for (size_t m = starts[r] * n; m < starts[r + 1] * n; ++m) {
      const size_t k = m / n;
      const TraceSample& now = run.samples[k];
      const double back = static_cast<double>(m) - period_s(now) / dv;
      if (back < 0) {
        ok = false;
        continue;
      }
      const auto j = static_cast<size_t>(back);
      const double w = back - static_cast<double>(j);
      // As many taps each side as the trace has (all of them but at its
      // start; j is at least a value before the trace's last).
      const auto half = static_cast<int>(std::min<size_t>(
          {static_cast<size_t>(FractionalDelay::kMaxHalf), j + 1, values - 1 - j}));
      if (w != delay.fraction() || half != delay.half()) delay.set(w, half);
      const TraceSample& before = run.samples[j / n];
      const double v_before = delay.at(compared, j);
      // A hold or the end of the pass that begins within this revolution
      // (a reaction to it) ends the comparison there; one in force at its
      // start, or in the revolution before, makes it not comparable.
      const bool stopped = !now.in_pass || (now.active & hold) != 0;
      if (stopped && k > starts[r]) break;
      // A sample without the vibration (a drive that has none, or a gap:
      // LinuxCNC's first periods before the sampler's first record) makes
      // its revolution, and the one that reads it as the one before, not
      // comparable; the rest of the trace is judged.
      if (std::isnan(compared(m)) || std::isnan(v_before)) {
        ok = false;
        continue;
      }
      ok = ok && !stopped && before.in_pass && now.engagement > kMinEngagement &&
           before.engagement > kMinEngagement && now.engagement >= before.engagement &&
           (before.active & hold) == 0;
      const double d = compared(m) - v_before;
      diff += d * d;
      energy += v_at(m) * v_at(m);
    }
    c.comparable = ok && energy > 0;
    c.q = energy > 0 ? std::sqrt(diff / energy) : 0;
    if (c.comparable && doubling) c.flip = halfway_share(r);
  }
  mark_onsets(out);
  return out;
}

std::vector<double> forced_vibration(const RunResult& run, Drive& twin) {
  std::vector<double> out;
  out.reserve(run.samples.size());
  DriveSample d;
  // The core steps the drive with the command of the tick before (none
  // before the first), and the trace keeps each tick's new command.
  double command = 0;
  for (size_t k = 0; k < run.samples.size(); ++k) {
    const TraceSample& s = run.samples[k];
    if (twin.step(command, d) != Status::kOk || std::abs(d.x_mm - s.x_mm) > 1e-6 ||
        d.pass_index != s.pass_index || d.in_pass != s.in_pass) {
      throw std::runtime_error(
          "forced_vibration: at sample " + std::to_string(k) + " (t = " + std::to_string(s.t_s) +
          " s) the twin is at x = " + std::to_string(d.x_mm) + " mm, pass " +
          std::to_string(d.pass_index) + ", the run at x = " + std::to_string(s.x_mm) +
          " mm, pass " + std::to_string(s.pass_index) +
          ": only a run with its program and spindle speed as loaded, "
          "every sample kept, can be replayed");
    }
    out.push_back(d.vibration_y_mm);
    command = s.feedrate_mm_s;
  }
  return out;
}

double first_onset_s(const RunResult& run, const std::vector<RevolutionChange>& changes) {
  for (const RevolutionChange& c : changes) {
    if (c.onset()) return run.samples[c.first_sample].t_s;
  }
  return -1;
}

void mark_onsets(std::vector<RevolutionChange>& out) {
  const size_t revs = out.size();
  for (RevolutionChange& c : out) c.onset_level = c.flip_onset_level = 0;
  // Entering the part the statistic starts high and falls as the engagement
  // settles; chatter makes it grow. Onset: a comparable revolution above the
  // threshold and above the one before, followed by a larger one -- or by
  // one that is not comparable any more (a hold or a rewrite reacting to it,
  // or the end of the pass). The growth may pause for one revolution that
  // stays above the threshold (chatter locking onto a spindle harmonic: the
  // paper's SMC II run gave 0.259 then 0.255), if the one after is larger
  // still or not comparable; a falling entry never passes that.
  for (size_t r = 2; r + 1 < revs; ++r) {
    const RevolutionChange &c = out[r], &next = out[r + 1];
    if (!c.comparable || !out[r - 1].comparable || c.q <= out[r - 1].q) continue;
    if (!next.comparable || next.q > c.q) {
      out[r].onset_level = c.q;
    } else if (r + 2 < revs && (!out[r + 2].comparable || out[r + 2].q > c.q)) {
      out[r].onset_level = std::min(c.q, next.q);
    }
  }
  // A period doubling: its share held for three revolutions (or up to a
  // reaction to it, or the pass's end). It repeats every revolution once it
  // has grown, and q saw it only while it grew: in the detector study's
  // full-width cuts q stayed at 0.02-0.10 while the share grew from below
  // 0.01 to 0.9 (edge/CHATTER.md, "Period doubling").
  for (size_t r = 0; r < revs; ++r) {
    if (!out[r].comparable || out[r].flip <= 0) continue;
    double level = out[r].flip;
    for (size_t j = r + 1; j <= r + 2 && j < revs && out[j].comparable; ++j) {
      level = std::min(level, out[j].flip);
    }
    out[r].flip_onset_level = level;
  }
}

smc::config::RunSummary summarize(const EdgeCore& core, const RunResult& run) {
  smc::config::RunSummary sum;
  const EdgeConfig& cfg = core.config();
  const EdgeParameters& p = cfg.params;
  sum.set_config_id(cfg.config_id);
  sum.set_variant(static_cast<smc::config::SmcVariant>(cfg.variant));
  sum.set_completed(run.completed);
  sum.set_passes_planned(cfg.program.count);

  // Pass runs from the events: started → completed, or aborted by a rewrite.
  struct PassRun {
    smc::config::PassSummary s;
    bool open = true;
  };
  std::vector<PassRun> runs;
  double done_t = -1, detected_t = -1;
  uint32_t rewrites = 0, chatter = 0, speed_changes = 0;
  for (const EdgeEvent& e : run.events) {
    switch (e.kind) {
      case EventKind::kSpeedChanged:
        ++speed_changes;
        break;
      case EventKind::kPassStarted: {
        if (!runs.empty() && runs.back().open) runs.back().open = false;
        PassRun r;
        r.s.set_index(static_cast<uint32_t>(e.pass_index));
        r.s.set_depth_mm(e.depth_mm);
        r.s.set_start_s(e.t_s);
        r.s.set_end_s(-1);
        r.s.set_contact_s(-1);
        runs.push_back(r);
        break;
      }
      case EventKind::kPassCompleted:
        if (!runs.empty() && runs.back().open) {
          runs.back().s.set_end_s(e.t_s);
          runs.back().open = false;
        }
        break;
      case EventKind::kProgramRewritten:
        ++rewrites;
        if (!runs.empty() && runs.back().open) {
          runs.back().s.set_end_s(e.t_s);
          runs.back().s.set_aborted(true);
          runs.back().s.set_chatter(true);
          runs.back().open = false;
        }
        break;
      case EventKind::kChatterDetected:
        ++chatter;
        if (detected_t < 0) detected_t = e.t_s;
        break;
      case EventKind::kChatterSignalled:
        ++chatter;
        break;
      case EventKind::kProgramDone:
        done_t = e.t_s;
        break;
      case EventKind::kFault:
        sum.add_faults(std::string(to_string(e.fault)) +
                       (e.fault == Fault::kModuleError && e.module >= 0
                            ? std::string(" in module ") + letter(static_cast<ModuleId>(e.module))
                            : std::string()) +
                       (e.why != nullptr ? std::string(" (") + e.why + ")" : std::string()) +
                       " at t=" + std::to_string(e.t_s) + " s");
        break;
      default:
        break;
    }
  }
  sum.set_program_rewrites(rewrites);
  sum.set_spindle_speed_changes(speed_changes);
  sum.set_tool_broken_s(run.tool_broken_s);
  {
    const auto& prog = core.program();
    sum.set_final_spindle_rpm(
        prog.count > 0 ? prog.passes[static_cast<size_t>(prog.count - 1)].spindle_rpm : 0.0);
  }
  sum.set_chatter_events(chatter);
  sum.set_chatter_detected_s(detected_t);

  // F_ref may change during a run (module M lowers it to hold the spindle
  // power): the summary's F_ref is the one at the first contact, and force
  // violations are measured against the F_ref in force at each revolution.
  double ref = run.revolutions.empty() ? 0 : run.revolutions.front().f_ref_n;
  double worst_force_ratio = -1;  // max over contact revolutions of F_Y / F_ref
  for (const auto& r : run.revolutions) {
    if (!r.contact || !(r.f_ref_n > 0)) continue;
    if (worst_force_ratio < 0) ref = r.f_ref_n;
    worst_force_ratio = std::max(worst_force_ratio, r.f_y_peak_n / r.f_ref_n);
  }
  sum.set_force_reference_n(ref);
  double peak_f = 0, peak_p = 0, peak_mean = 0;
  for (const auto& r : run.revolutions) {
    peak_f = std::max(peak_f, r.f_y_peak_n);
    peak_p = std::max(peak_p, r.power_peak_w);
    peak_mean = std::max(peak_mean, r.power_mean_w);
  }
  sum.set_peak_mean_power_w(peak_mean);
  sum.set_peak_mean_power_violation_pct(100.0 * (peak_mean - p.max_spindle_power_w) /
                                        p.max_spindle_power_w);
  sum.set_peak_force_n(peak_f);
  sum.set_peak_force_violation_pct(worst_force_ratio > 0 ? 100.0 * (worst_force_ratio - 1) : 0);
  sum.set_peak_power_w(peak_p);
  sum.set_peak_power_violation_pct(100.0 * (peak_p - p.max_spindle_power_w) /
                                   p.max_spindle_power_w);

  // Per pass: overshoot over contact revolutions, steady-state error over
  // fully engaged revolutions after the controller has settled (5 time
  // constants after full engagement or after a hold).
  const bool model = (cfg.modules & bit(ModuleId::L)) != 0;
  const double tau = model ? p.model_time_constant_s : p.adaptive_time_constant_s;
  const ModuleMask hold_mask = static_cast<ModuleMask>(bit(ModuleId::C) | bit(ModuleId::G));
  double worst_overshoot = -1e9, worst_sse = 0, depth_removed = 0;
  // Steady mean spindle power: from kPowerSettleRevolutions after a pass's
  // first contact to its end, revolutions in a hold left out.
  constexpr int kPowerSettleRevolutions = 10;
  double steady_power = 0;
  uint32_t steady_power_revs = 0;
  uint32_t completed = 0;
  for (PassRun& pr : runs) {
    const double t0 = pr.s.start_s();
    const double t1 = pr.s.end_s() < 0 ? run.end_time_s + 1 : pr.s.end_s();
    double max_ratio = 0, err_sum = 0;
    int err_n = 0, settled = 0, since_contact = 0;
    bool any_contact = false;
    for (const auto& r : run.revolutions) {
      if (r.t_s <= t0 || r.t_s > t1) continue;
      const bool held = (r.active & hold_mask) != 0 || r.fault_hold;
      if (r.chatter) pr.s.set_chatter(true);
      if (!r.contact || held) {
        settled = 0;
        continue;
      }
      if (!any_contact) pr.s.set_contact_s(r.t_s);
      any_contact = true;
      if (++since_contact > kPowerSettleRevolutions) {
        steady_power = std::max(steady_power, r.power_mean_w);
        ++steady_power_revs;
      }
      if (r.f_ref_n > 0) max_ratio = std::max(max_ratio, r.f_y_peak_n / r.f_ref_n);
      const bool engaged = !std::isnan(r.engagement_min) && r.engagement_min >= 0.99;
      settled = engaged ? settled + 1 : 0;
      const double revolution_s = r.period_s > 0 ? r.period_s : p.slow_period_s;
      if (settled > static_cast<int>(std::ceil(5 * tau / revolution_s)) && r.f_ref_n > 0) {
        err_sum += std::fabs(r.f_y_peak_n - r.f_ref_n) / r.f_ref_n;
        ++err_n;
      }
    }
    if (any_contact && max_ratio > 0) {
      pr.s.set_overshoot_pct(100.0 * (max_ratio - 1));
      worst_overshoot = std::max(worst_overshoot, pr.s.overshoot_pct());
    }
    if (err_n > 0) {
      pr.s.set_steady_state_error_pct(100.0 * err_sum / err_n);
      worst_sse = std::max(worst_sse, pr.s.steady_state_error_pct());
    }
    pr.s.set_steady_state_revolutions(static_cast<uint32_t>(err_n));
    if (!pr.s.aborted() && pr.s.end_s() >= 0) {
      ++completed;
      depth_removed += pr.s.depth_mm();
    }
    *sum.add_passes() = pr.s;
  }
  sum.set_steady_mean_power_w(steady_power);
  sum.set_steady_power_revolutions(steady_power_revs);
  sum.set_passes_completed(completed);
  sum.set_depth_removed_mm(depth_removed);
  sum.set_overshoot_pct(worst_overshoot > -1e9 ? worst_overshoot : 0);
  sum.set_steady_state_error_pct(worst_sse);
  sum.set_cycle_time_s(done_t >= 0 ? done_t : run.end_time_s);

  double hold_s = 0;
  for (const auto& r : run.revolutions) {
    if ((r.active & bit(ModuleId::C)) != 0) hold_s += r.period_s;
  }
  sum.set_feed_hold_s(hold_s);
  const double onset = first_onset_s(run, vibration_change(run, p.slow_period_s, p.teeth));
  sum.set_chatter_onset_s(onset);
  sum.set_detection_delay_s(onset >= 0 && detected_t >= 0 ? detected_t - onset : -1);
  return sum;
}

}  // namespace smc::edge
