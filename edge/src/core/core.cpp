#include "smc/edge/core.hpp"

#include <algorithm>
#include <cmath>

namespace smc::edge {

namespace {

bool is_active(ModuleMask mask, ModuleId id) noexcept { return (mask & bit(id)) != 0; }

}  // namespace

const char* to_string(Fault f) noexcept {
  switch (f) {
    case Fault::kNone:
      return "none";
    case Fault::kNonFiniteForce:
      return "non-finite force sample";
    case Fault::kSaturatedForce:
      return "saturated force sample";
    case Fault::kModuleError:
      return "module error";
    case Fault::kOverrun:
      return "real-time loop overrun";
    case Fault::kSupervisorError:
      return "operation supervisor reached no stable situation";
    case Fault::kDriveError:
      return "drive error";
  }
  return "unknown";
}

const char* to_string(EventKind k) noexcept {
  switch (k) {
    case EventKind::kSituationChanged:
      return "situation";
    case EventKind::kChatterDetected:
      return "chatter_detected";
    case EventKind::kChatterSignalled:
      return "chatter_signalled";
    case EventKind::kProgramRewritten:
      return "program_rewritten";
    case EventKind::kFault:
      return "fault";
    case EventKind::kFaultCleared:
      return "fault_cleared";
    case EventKind::kPassStarted:
      return "pass_started";
    case EventKind::kPassCompleted:
      return "pass_completed";
    case EventKind::kProgramDone:
      return "program_done";
    case EventKind::kToolBroken:
      return "tool_broken";
    case EventKind::kSpeedChanged:
      return "speed_changed";
  }
  return "unknown";
}

EdgeCore::EdgeCore(EdgeConfig config, Drive& drive, const ModuleRegistry& registry)
    : config_(std::move(config)), drive_(drive) {
  running_.program = config_.program;
  // Every module of the registry is built (an unconfigured one never runs);
  // the schedule follows the registry's data-flow order and each module's
  // declarations.
  auto add = [](auto& list, int& n, Module* m) { list[static_cast<size_t>(n++)] = m; };
  for (const ModuleEntry& e : registry) {
    auto& slot = modules_[static_cast<size_t>(e.id)];
    if (slot) {
      throw ConfigError(std::string("module registry: module ") + letter(e.id) +
                        " is listed twice");
    }
    slot = e.make();
    Module* m = slot.get();
    if (is_active(config_.modules, e.id)) m->configure(config_.params);
    m->attach(running_);
    if (m->takes_samples()) add(schedule_.sample, schedule_.n_sample, m);
    if (m->starts_on_activation()) add(schedule_.starting, schedule_.n_starting, m);
    if (m->resets_on_activation()) restarting_ = static_cast<ModuleMask>(restarting_ | bit(e.id));
    if (m->supervisory() && is_active(config_.modules, e.id)) {
      supervisory_ = static_cast<ModuleMask>(supervisory_ | bit(e.id));
    }
    if (m->after_supervisor()) {
      add(schedule_.after_supervisor, schedule_.n_after, m);
      continue;
    }
    switch (m->period()) {
      case Period::kRevolution:
        add(schedule_.revolution, schedule_.n_revolution, m);
        break;
      case Period::kFast:
        add(schedule_.fast, schedule_.n_fast, m);
        break;
      case Period::kEvent:
        add(schedule_.event, schedule_.n_event, m);
        break;
    }
  }
  for (int i = 0; i < kMaxModules; ++i) {
    if (is_active(config_.modules, static_cast<ModuleId>(i)) && !modules_[static_cast<size_t>(i)]) {
      throw ConfigError(common::Diagnostic{
          "supervisor_config.modules",
          std::string("module ") + letter(static_cast<ModuleId>(i)) + " is not one this edge has",
          "use the modules of the edge's registry"});
    }
  }
  if (is_active(config_.modules, ModuleId::O) && !drive_.can_change_spindle_speed()) {
    throw ConfigError(common::Diagnostic{
        "supervisor_config.modules",
        "module O (spindle-speed chatter suppressor) needs a drive that can change the spindle "
        "speed, and this one cannot",
        "use SMC II (added passes) on this machine, or a drive with a spindle speed override"});
  }
  supervisor_ = config_.grafcet ? std::make_unique<OperationSupervisor>(*config_.grafcet)
                                : std::make_unique<OperationSupervisor>(
                                      config_.grafcet_text, config_.grafcet_name, config_.modules);
}

EdgeCore::~EdgeCore() = default;

void EdgeCore::start() {
  running_.program = config_.program;
  running_.current_pass = 0;
  drive_.load(running_.program);
  s_ = Signals{};
  for (auto& m : modules_) {
    if (!m) continue;
    m->reset();
    m->clear_outputs(s_);
  }
  supervisor_->reset();
  situation_ = Situation{};
  drive_sample_ = DriveSample{};
  fault_ = Fault::kNone;
  fault_hold_ = false;
  ticks_ = 0;
  revolution_phase_ = 0;
  revolution_samples_ = 0;
  chatter_events_ = 0;
  power_peak_w_ = 0;
  peak_force_n_ = 0;
  power_sum_w_ = 0;
  power_samples_ = 0;
  engagement_min_ = 1;
  last_pass_ = -1;
  last_in_pass_ = false;
  last_done_ = false;
  speed_change_pass_ = -1;
  ledge_count_ = 0;
  applied_speed_rpm_ = 0;
  ident_pass_ = -1;
  ident_revolutions_ = 0;
  ident_level_ = 0;
  ident_held_ = 0;
  ident_done_ = false;
  ident_factor_ = 1;
  batch_ = ForceBatchRecord{};
}

void EdgeCore::advance_identification() noexcept {
  const EdgeParameters& p = config_.params;
  const double was = ident_factor_;
  ident_factor_ = 1;
  if (p.identification_revolutions <= 0) return;
  const int pass = running_.current_pass;
  if (pass < 0 || pass != running_.program.count - 1 || !s_.contact) return;
  if (pass != ident_pass_) {
    ident_pass_ = pass;
    ident_revolutions_ = 0;
    ident_level_ = 0;
    ident_held_ = 0;
  }
  if (ident_revolutions_ < EdgeParameters::kIdentificationSettle) ++ident_revolutions_;
  if (ident_revolutions_ < EdgeParameters::kIdentificationSettle) return;
  // Towards the level in force (back to 1 once the segment is done) by a
  // ramp, then the level's revolutions.
  const double ramp = EdgeParameters::kIdentificationRamp;
  const double target = ident_done_ ? 1.0 : p.identification_levels[ident_level_];
  ident_factor_ = std::clamp(target, was * (1.0 - ramp), was * (1.0 + ramp));
  if (ident_done_ || ident_factor_ != target) return;
  if (++ident_held_ < p.identification_revolutions) return;
  ident_held_ = 0;
  if (++ident_level_ >= p.identification_level_count) ident_done_ = true;
}

EdgeEvent EdgeCore::make_event(EventKind kind) const noexcept {
  EdgeEvent e;
  e.kind = kind;
  e.t_s = drive_sample_.force.t_s;
  e.active_steps = situation_.active_steps;
  e.active = s_.active;
  e.inputs = situation_.inputs;
  e.pass_index = static_cast<int16_t>(drive_sample_.pass_index);
  e.pass_count = static_cast<int16_t>(running_.program.count);
  e.depth_mm = drive_sample_.depth_mm;
  return e;
}

void EdgeCore::emit(EventKind kind) noexcept { events_.try_push(make_event(kind)); }

void EdgeCore::raise_fault(Fault f, int module, double value, const char* why) noexcept {
  if (fault_hold_) return;  // the first cause is the one reported
  fault_ = f;
  fault_hold_ = true;
  fault_releases_ = pending_inputs_.releases;
  EdgeEvent e = make_event(EventKind::kFault);
  e.fault = f;
  e.module = static_cast<int8_t>(module);
  e.value = value;
  e.why = why;
  events_.try_push(e);
}

void EdgeCore::run_module(Module& m, bool sample_hook) noexcept {
  const int id = static_cast<int>(m.id());
  if (!check_declarations_) {
    const Status st = sample_hook ? m.on_sample(s_) : m.update(s_);
    if (st != Status::kOk) raise_fault(Fault::kModuleError, id, 0, m.error_reason());
    return;
  }
  const Signals before = s_;
  const Status st = sample_hook ? m.on_sample(s_) : m.update(s_);
  const SignalMask undeclared = changed_signals(before, s_) & ~m.writes();
  if (st != Status::kOk || undeclared != 0) {
    raise_fault(Fault::kModuleError, id, undeclared,
                st != Status::kOk ? m.error_reason() : "it wrote signals it does not declare");
  }
}

ModuleMask EdgeCore::apply_situation() noexcept {
  const ModuleMask before = s_.active;
  const ModuleMask after = static_cast<ModuleMask>(situation_.active & config_.modules);
  // Impulse actions reset modules; a routine that becomes active starts afresh.
  ModuleMask resets = static_cast<ModuleMask>(situation_.impulses & config_.modules);
  resets = static_cast<ModuleMask>(resets | (after & ~before & restarting_));
  // Receptivity h: module O has had its go in this pass.
  if ((after & ~before & bit(ModuleId::O)) != 0) speed_change_pass_ = running_.current_pass;
  for (int i = 0; i < kMaxModules; ++i) {
    Module* m = modules_[static_cast<size_t>(i)].get();
    if ((resets & (1u << i)) == 0 || m == nullptr) continue;
    m->reset();
    m->clear_outputs(s_);
  }
  s_.active = after;
  // Active now, and either not active before or reset this tick.
  return static_cast<ModuleMask>(after & (~before | resets));
}

bool EdgeCore::advance_revolution_clock() noexcept {
  const EdgeParameters& p = config_.params;
  // One revolution per 60 / rpm s of the measured speed; while the spindle is
  // still (or slower than the supervised range) the slow period stands in,
  // so that monitoring and telemetry go on.
  const double rpm = s_.spindle_rpm;
  const double step = std::isfinite(rpm) && rpm >= p.min_spindle_rpm
                          ? rpm / 60.0 * p.sample_period_s
                          : 1.0 / p.samples_per_revolution;
  revolution_phase_ += step;
  ++revolution_samples_;
  // A revolution ends on the sample that completes it; a whole number of
  // samples per revolution (80 at 1500 rpm and 0.5 ms) must not slip by one
  // through rounding, and a revolution never outgrows the modules' buffers.
  if (revolution_phase_ < 1.0 - 1e-9 && revolution_samples_ < p.max_samples_per_revolution) {
    return false;
  }
  revolution_phase_ = std::max(0.0, revolution_phase_ - 1.0);
  if (revolution_phase_ < 1e-9) revolution_phase_ = 0;
  s_.revolution_samples = revolution_samples_;
  s_.revolution_period_s = revolution_samples_ * p.sample_period_s;
  revolution_samples_ = 0;
  return true;
}

bool EdgeCore::crossing_ledge() const noexcept {
  const int pass = drive_sample_.pass_index;
  if (!drive_sample_.in_pass || pass < 0 || pass >= running_.program.count) return false;
  const double top = running_.program.depth_before(pass);
  // From where the cutter's leading edge first reaches material beyond the
  // ledge (a diameter before where the aborted pass stopped) to a radius
  // past it. Without the cutter's radius, the whole pass.
  const double r = config_.params.cutter_radius_mm;
  for (int i = 0; i < ledge_count_; ++i) {
    const Ledge& l = ledges_[static_cast<size_t>(i)];
    if (!(top < l.depth_mm - 1e-9)) continue;  // cut below it already
    if (!(r > 0)) return true;
    const double x = drive_sample_.x_mm;
    if (x >= l.x_mm - 2 * r && x <= l.x_mm + r) return true;
  }
  return false;
}

void EdgeCore::tick(bool overrun) noexcept {
  ++ticks_;
  const EdgeParameters& p = config_.params;
  s_.operator_inputs = pending_inputs_;
  s_.f_y_updated = false;
  s_.program_rewritten = false;
  const bool broken_before = s_.tool_broken;  // N decides on samples

  // 1. The machine: apply the last feed command, read the sample.
  if (drive_.step(s_.feedrate_cmd_mm_s, drive_sample_) != Status::kOk) {
    raise_fault(Fault::kDriveError, -1, 0);
  }
  running_.current_pass = drive_sample_.pass_index;
  s_.spindle_rpm = drive_sample_.spindle_rpm;
  s_.depth_mm = drive_sample_.depth_mm;
  s_.programmed_feedrate_mm_s = drive_sample_.programmed_feedrate_mm_s;
  s_.in_pass = drive_sample_.in_pass;
  s_.spindle_power_w = drive_sample_.spindle_power_w;
  s_.engagement = drive_sample_.engagement;
  s_.crossing_ledge = crossing_ledge();
  s_.speed_changed_in_pass =
      speed_change_pass_ >= 0 && speed_change_pass_ == drive_sample_.pass_index;
  const int pass = drive_sample_.pass_index;
  const double planned = pass >= 0 && pass < running_.program.count
                             ? running_.program.passes[static_cast<size_t>(pass)].force_reference_n
                             : 0.0;
  s_.force_reference_planned = planned > 0;
  s_.force_reference_base_n = planned > 0 ? planned : p.force_reference_at(s_.spindle_rpm);
  s_.force_reference_n = s_.force_reference_base_n * s_.force_reference_scale * ident_factor_;
  if (std::isfinite(drive_sample_.spindle_power_w)) {
    power_peak_w_ = std::max(power_peak_w_, drive_sample_.spindle_power_w);
    power_sum_w_ += drive_sample_.spindle_power_w;
    ++power_samples_;
  }
  engagement_min_ = std::isnan(drive_sample_.engagement)
                        ? drive_sample_.engagement
                        : std::min(engagement_min_, drive_sample_.engagement);

  // 2. A bad sample never reaches the modules; it holds the feed.
  const ForceSample& f = drive_sample_.force;
  bool sample_ok = std::isfinite(f.f_x_n) && std::isfinite(f.f_y_n) && std::isfinite(f.f_z_n);
  if (!sample_ok) {
    raise_fault(Fault::kNonFiniteForce, -1, std::isfinite(f.f_y_n) ? f.f_z_n : f.f_y_n);
  } else if (std::fabs(f.f_y_n) >= p.force_sensor_range_n ||
             std::fabs(f.f_z_n) >= p.force_sensor_range_n) {
    sample_ok = false;
    raise_fault(Fault::kSaturatedForce, -1, std::max(std::fabs(f.f_y_n), std::fabs(f.f_z_n)));
  }
  if (overrun) raise_fault(Fault::kOverrun, -1, 0);
  if (sample_ok) {
    s_.sample = f;
    s_.revolution_phase = revolution_phase_;
    for (int i = 0; i < schedule_.n_sample; ++i) {
      Module& m = *schedule_.sample[static_cast<size_t>(i)];
      if (is_active(s_.active | supervisory_, m.id())) run_module(m, true);
    }
    if (ticks_ % static_cast<uint64_t>(decimation_) == 0 && batch_.count < ForceBatchRecord::kMax) {
      if (batch_.count == 0) {
        batch_.first_t_s = f.t_s;
        batch_.period_s = p.sample_period_s * decimation_;
      }
      batch_.f_y[batch_.count] = static_cast<float>(f.f_y_n);
      batch_.f_z[batch_.count] = static_cast<float>(f.f_z_n);
      ++batch_.count;
    }
  }

  const bool revolution = advance_revolution_clock();
  const bool fast = ticks_ % static_cast<uint64_t>(p.samples_per_fast) == 0;
  const bool chatter_before = s_.chatter_detected;

  // 3. Revolution-rate modules, in data-flow order (paper: I, J, E, H, K, L).
  if (revolution) {
    for (int i = 0; i < schedule_.n_revolution; ++i) {
      Module& m = *schedule_.revolution[static_cast<size_t>(i)];
      if (is_active(s_.active | supervisory_, m.id())) run_module(m, false);
    }
    advance_identification();
  }
  // 4. Fast modules (B, D, G), then the configured event modules another
  // module asked for (F, when G asks).
  if (fast) {
    for (int i = 0; i < schedule_.n_fast; ++i) {
      Module& m = *schedule_.fast[static_cast<size_t>(i)];
      if (is_active(s_.active | supervisory_, m.id())) run_module(m, false);
    }
    for (int i = 0; i < schedule_.n_event; ++i) {
      Module& m = *schedule_.event[static_cast<size_t>(i)];
      if (is_active(config_.modules, m.id()) && m.requested(s_)) run_module(m, false);
    }
    // O's speed command: to the drive, and the program's passes from here on.
    if (s_.spindle_speed_cmd_rpm > 0 && s_.spindle_speed_cmd_rpm != applied_speed_rpm_) {
      applied_speed_rpm_ = s_.spindle_speed_cmd_rpm;
      FixedProgram& prog = running_.program;
      for (int i = std::max(0, running_.current_pass); i < prog.count; ++i) {
        prog.passes[static_cast<size_t>(i)].spindle_rpm = applied_speed_rpm_;
      }
      ++prog.revision;
      if (drive_.change_spindle_speed(applied_speed_rpm_) != Status::kOk) {
        raise_fault(Fault::kDriveError, -1, applied_speed_rpm_);
      }
      programs_.try_push(prog);
      EdgeEvent e = make_event(EventKind::kSpeedChanged);
      e.value = applied_speed_rpm_;
      e.frequency_hz = s_.chatter_frequency_hz;
      events_.try_push(e);
    }
    if (s_.program_rewritten) {
      // The aborted pass stops here, cut to its depth behind the cutter
      // (the passes before it are as they were).
      if (ledge_count_ < static_cast<int>(ledges_.size()) && drive_sample_.in_pass) {
        ledges_[static_cast<size_t>(ledge_count_++)] = {
            drive_sample_.x_mm,
            running_.program.depth_before(running_.current_pass) + drive_sample_.depth_mm};
      }
      if (drive_.rewrite(running_.program, running_.current_pass) != Status::kOk) {
        raise_fault(Fault::kDriveError, -1, 0);
      }
      programs_.try_push(running_.program);
      emit(EventKind::kProgramRewritten);
      // The identification segment belongs to the program's last pass: a
      // rewritten program has a new one, and the segment runs there again.
      ident_pass_ = -1;
      ident_done_ = false;
      ident_factor_ = 1;
    }
  }

  // 5. State supervisor → operation supervisor → module activity.
  const uint64_t steps_before = situation_.active_steps;
  situation_ = supervisor_->evaluate(receptivities(s_, fault_hold_));
  if (situation_.error) raise_fault(Fault::kSupervisorError, -1, 0);
  const ModuleMask started = apply_situation();
  // Modules whose first output is due at once (K, L) give it now, before A.
  for (int i = 0; i < schedule_.n_starting; ++i) {
    Module& m = *schedule_.starting[static_cast<size_t>(i)];
    if ((started & bit(m.id())) != 0) run_module(m, false);
  }

  // 6. Modules that act on this tick's decision (A, so a hold acts at once:
  // also between fast periods when the feed hold C has just started, as
  // when N latches a breakage on a sample).
  if (fast || (started & bit(ModuleId::C)) != 0) {
    for (int i = 0; i < schedule_.n_after; ++i) {
      Module& m = *schedule_.after_supervisor[static_cast<size_t>(i)];
      if (is_active(s_.active | supervisory_, m.id())) run_module(m, false);
    }
  }
  if (fault_hold_) {
    s_.feedrate_cmd_mm_s = 0;
    s_.feed_per_tooth_cmd_mm = 0;
  }

  // 7. Events.
  if (fault_hold_ && s_.operator_inputs.releases != fault_releases_) {
    fault_hold_ = false;
    emit(EventKind::kFaultCleared);
  }
  if (s_.chatter_detected && !chatter_before) {
    ++chatter_events_;
    EdgeEvent e = make_event(EventKind::kChatterDetected);
    e.ratio = s_.chatter_ratio;
    e.frequency_hz = s_.chatter_frequency_hz;
    events_.try_push(e);
  }
  if (s_.tool_broken && !broken_before) {
    // The feed is held from this tick (step 9); the tool leaves the part
    // where the drive can lift it.
    const bool retracted = drive_.can_retract() && drive_.retract() == Status::kOk;
    EdgeEvent e = make_event(EventKind::kToolBroken);
    e.module = static_cast<int8_t>(s_.breakage_window);
    e.value = s_.breakage_drop;
    e.ratio = retracted ? 1.0 : 0.0;
    events_.try_push(e);
  }
  if (s_.chatter_signalled && fast) {
    ++chatter_events_;
    emit(EventKind::kChatterSignalled);
  }
  if (situation_.active_steps != steps_before) emit(EventKind::kSituationChanged);
  if (drive_sample_.in_pass && (!last_in_pass_ || drive_sample_.pass_index != last_pass_)) {
    emit(EventKind::kPassStarted);
  }
  if (!drive_sample_.in_pass && last_in_pass_) {
    EdgeEvent e = make_event(EventKind::kPassCompleted);
    e.pass_index = static_cast<int16_t>(last_pass_);
    events_.try_push(e);
  }
  if (drive_sample_.program_done && !last_done_) emit(EventKind::kProgramDone);
  last_in_pass_ = drive_sample_.in_pass;
  last_pass_ = drive_sample_.pass_index;
  last_done_ = drive_sample_.program_done;

  // 8. Telemetry, once per revolution.
  if (revolution) {
    RevolutionRecord r;
    r.t_s = f.t_s;
    r.period_s = s_.revolution_period_s;
    r.revolution = s_.revolutions;
    r.f_y_peak_n = s_.f_y_peak_n;
    if (s_.contact) peak_force_n_ = std::max(peak_force_n_, s_.f_y_peak_n);
    r.f_ref_n = s_.force_reference_n;
    r.feedrate_mm_s = s_.feedrate_cmd_mm_s;
    r.feed_per_tooth_mm = s_.feed_per_tooth_cmd_mm;
    r.depth_mm = s_.depth_mm;
    r.spindle_rpm = s_.spindle_rpm;
    r.power_peak_w = power_peak_w_;
    // The drive's spindle power; M's estimate from the forces when it has none.
    r.power_mean_w = power_samples_ > 0 ? power_sum_w_ / power_samples_ : s_.power_mean_w;
    r.x_mm = drive_sample_.x_mm;
    r.chatter_ratio = s_.chatter_ratio;
    r.chatter_vibration_ratio = s_.chatter_vibration_ratio;
    r.chatter_vibration_flip = s_.chatter_vibration_flip;
    r.gain_estimate = s_.gain_estimate;
    r.engagement_min = engagement_min_;
    r.pass_index = static_cast<int16_t>(drive_sample_.pass_index);
    r.pass_count = static_cast<int16_t>(running_.program.count);
    r.contact = s_.contact;
    r.chatter = s_.chatter_detected;
    r.fault_hold = fault_hold_;
    r.active = s_.active;
    r.active_steps = situation_.active_steps;
    revolutions_.try_push(r);
    power_peak_w_ = 0;
    power_sum_w_ = 0;
    power_samples_ = 0;
    engagement_min_ = 1;
    if (batch_.count > 0) batches_.try_push(batch_);
    batch_.count = 0;
  }
}

}  // namespace smc::edge
