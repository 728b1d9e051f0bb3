#pragma once
// The edge core: one tick per force sample. Reads the drive, runs the
// modules at their periods, evaluates the state and operation supervisors,
// commands the feed, and hands telemetry and events to whoever drains its
// rings (the comms thread, or the virtual-time runner).
//
// Real-time contract: tick() and set_operator_inputs() never allocate, lock,
// log, throw or call DDS. Everything else runs before the loop.

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "smc/edge/drive.hpp"
#include "smc/edge/module.hpp"
#include "smc/edge/parameters.hpp"
#include "smc/edge/program.hpp"
#include "smc/edge/registry.hpp"
#include "smc/edge/rt/spsc_ring.hpp"
#include "smc/edge/signals.hpp"
#include "smc/edge/supervisor.hpp"
#include "smc/supervision/config.hpp"

namespace smc::config {
class SupervisorConfig;
}

namespace smc::edge {

// Everything the core needs, validated, built off the loop (the shared
// validation of services/supervision).
using EdgeConfig = supervision::ValidatedConfig;

// Reads and checks a supervisor configuration for this edge: the shared
// validation (parameters, module set, part program within the machine's
// limits, the Grafcet parsed, bound and verified), then the edge's own
// checks against `registry`: every configured module is one the edge has,
// and no two configured modules declare the same output signals. Throws
// ConfigError listing every problem.
EdgeConfig edge_config_from_proto(const smc::config::SupervisorConfig& cfg,
                                  const ModuleRegistry& registry = paper_modules());

enum class EventKind : uint8_t {
  kSituationChanged,
  kChatterDetected,   // automatic (E)
  kChatterSignalled,  // operator (D)
  kProgramRewritten,  // F added a pass
  kFault,             // the core put the machine in feed hold
  kFaultCleared,
  kPassStarted,
  kPassCompleted,
  kProgramDone,
  kToolBroken,    // N latched a breakage: window in `module`, its drop in `value`,
                  // `ratio` 1 when the drive retracted the tool
  kSpeedChanged,  // O changed the spindle speed: the new speed in `value` (rpm)
};
const char* to_string(EventKind k) noexcept;

struct EdgeEvent {
  EventKind kind = EventKind::kSituationChanged;
  double t_s = 0;
  Fault fault = Fault::kNone;
  int8_t module = -1;  // ModuleId for kModuleError, else -1
  // kModuleError: the module's reason (Module::error_reason, a static
  // string), or nullptr.
  const char* why = nullptr;
  uint64_t active_steps = 0;
  ModuleMask active = 0;
  uint32_t inputs = 0;
  int16_t pass_index = 0;
  int16_t pass_count = 0;
  double depth_mm = 0;
  double ratio = 0;         // chatter statistic
  double frequency_hz = 0;  // chatter frequency
  double value = 0;         // the offending sample for a force fault
};

// One record per spindle revolution (module I's period).
struct RevolutionRecord {
  double t_s = 0;
  double period_s = 0;  // how long the revolution took (the revolution clock)
  uint32_t revolution = 0;
  double f_y_peak_n = 0;
  double f_ref_n = 0;
  double feedrate_mm_s = 0;
  double feed_per_tooth_mm = 0;
  double depth_mm = 0;
  double spindle_rpm = 0;
  double power_peak_w = 0;  // highest instantaneous spindle power in the revolution
  double power_mean_w = 0;  // spindle power averaged over the revolution
  double x_mm = 0;
  double chatter_ratio = 0;
  double chatter_vibration_ratio = 0;  // E's q (0: not judged, or no estimate)
  double chatter_vibration_flip = 0;   // E's period-doubling share (0: not judged)
  double gain_estimate = 0;
  double engagement_min = 0;  // lowest engagement during the revolution (NaN: unknown)
  int16_t pass_index = 0;
  int16_t pass_count = 0;
  bool contact = false;
  bool chatter = false;
  bool fault_hold = false;
  ModuleMask active = 0;
  uint64_t active_steps = 0;
};

// Raw force of one revolution, decimated.
struct ForceBatchRecord {
  static constexpr int kMax = 128;
  double first_t_s = 0;
  double period_s = 0;
  uint16_t count = 0;
  std::array<float, kMax> f_y{};
  std::array<float, kMax> f_z{};
};

class EdgeCore {
 public:
  // Not real-time. Builds the modules of `registry` and the supervisors from
  // a validated configuration, and the schedule from the modules'
  // declarations in the registry's data-flow order.
  EdgeCore(EdgeConfig config, Drive& drive, const ModuleRegistry& registry = paper_modules());
  ~EdgeCore();
  EdgeCore(const EdgeCore&) = delete;
  EdgeCore& operator=(const EdgeCore&) = delete;

  // Not real-time: load the program into the drive, reset every module and
  // the supervisors. Call before the first tick.
  void start();
  // Real-time: one sample period. `overrun`: the loop missed its deadline.
  void tick(bool overrun = false) noexcept;
  // Real-time: the latest operator inputs (the comms side delivers them).
  void set_operator_inputs(const OperatorInputs& in) noexcept { pending_inputs_ = in; }
  // Raw-force decimation for ForceBatchRecord (1 = every sample).
  void set_batch_decimation(int d) noexcept { decimation_ = d < 1 ? 1 : d; }
  // Check every module run against its declared writes: a module that
  // changes a signal group it did not declare faults (kModuleError). For
  // tests; costs a copy of the signals per module run.
  void set_check_declarations(bool on) noexcept { check_declarations_ = on; }

  const Signals& signals() const noexcept { return s_; }
  const Situation& situation() const noexcept { return situation_; }
  const DriveSample& drive_sample() const noexcept { return drive_sample_; }
  const FixedProgram& program() const noexcept { return running_.program; }
  const EdgeConfig& config() const noexcept { return config_; }
  const OperationSupervisor& supervisor() const noexcept { return *supervisor_; }
  Fault fault() const noexcept { return fault_; }
  bool fault_hold() const noexcept { return fault_hold_; }
  bool done() const noexcept { return drive_sample_.program_done; }
  uint64_t ticks() const noexcept { return ticks_; }
  uint32_t chatter_events() const noexcept { return chatter_events_; }
  // The largest per-revolution F_Y peak in contact since start(), kept by the
  // loop itself: the job's figure, whatever the telemetry ring had to drop.
  double peak_force_n() const noexcept { return peak_force_n_; }
  uint64_t dropped_events() const noexcept { return events_.dropped(); }

  rt::SpscRing<EdgeEvent, 1024>& events() noexcept { return events_; }
  rt::SpscRing<RevolutionRecord, 256>& revolutions() noexcept { return revolutions_; }
  rt::SpscRing<ForceBatchRecord, 16>& batches() noexcept { return batches_; }
  // The program after every rewrite (module F), for the comms side.
  rt::SpscRing<FixedProgram, 4>& programs() noexcept { return programs_; }

 private:
  // Modules in data-flow order, by when they run.
  struct Schedule {
    template <class T>
    using List = std::array<T, kMaxModules>;
    List<Module*> sample{}, revolution{}, fast{}, event{}, after_supervisor{}, starting{};
    int n_sample = 0, n_revolution = 0, n_fast = 0, n_event = 0, n_after = 0, n_starting = 0;
  };

  void raise_fault(Fault f, int module, double value, const char* why = nullptr) noexcept;
  void run_module(Module& m, bool sample_hook) noexcept;
  // Applies the new situation; returns the modules that started (became
  // active or were reset) in this tick.
  ModuleMask apply_situation() noexcept;
  // Configured modules that run under the state supervisor (M), whatever
  // the operation supervisor's situation.
  ModuleMask supervisory_ = 0;
  // Modules reset whenever they become active (G, O).
  ModuleMask restarting_ = 0;
  // The pass in which module O last ran (-1: none): receptivity h.
  int speed_change_pass_ = -1;
  double applied_speed_rpm_ = 0;  // O's last command passed to the drive
  // The ledges aborted passes left: where each stopped (the drive's x) and
  // the depth it had cut to there. A later pass that starts above one meets
  // a step in its depth while it crosses it (Signals::crossing_ledge).
  struct Ledge {
    double x_mm = 0;
    double depth_mm = 0;
  };
  std::array<Ledge, FixedProgram::kMaxPasses> ledges_{};
  int ledge_count_ = 0;
  bool crossing_ledge() const noexcept;
  void emit(EventKind kind) noexcept;
  EdgeEvent make_event(EventKind kind) const noexcept;

  EdgeConfig config_;
  Drive& drive_;
  std::array<std::unique_ptr<Module>, kMaxModules> modules_;  // by ModuleId
  Schedule schedule_;
  std::unique_ptr<OperationSupervisor> supervisor_;
  RunningProgram running_;
  bool check_declarations_ = false;
  Signals s_;
  Situation situation_;
  DriveSample drive_sample_;
  OperatorInputs pending_inputs_;
  Fault fault_ = Fault::kNone;
  bool fault_hold_ = false;
  uint32_t fault_releases_ = 0;
  uint64_t ticks_ = 0;
  // The revolution clock: the share of a revolution turned since the last
  // revolution tick, advanced each sample by the measured spindle speed.
  double revolution_phase_ = 0;
  int revolution_samples_ = 0;
  // Advances the clock by one sample; true when a revolution ends here.
  bool advance_revolution_clock() noexcept;
  uint32_t chatter_events_ = 0;
  double power_peak_w_ = 0;
  double peak_force_n_ = 0;
  double power_sum_w_ = 0;
  int power_samples_ = 0;
  double engagement_min_ = 1;
  int last_pass_ = -1;
  bool last_in_pass_ = false;
  bool last_done_ = false;
  // The identification segment (supervision/parameters.hpp): the last pass
  // it counts contact revolutions in, how many, the level it is at and the
  // revolutions held there, whether it has run, and the factor on F_ref now.
  // Advanced once per revolution, after the modules.
  int ident_pass_ = -1;
  int ident_revolutions_ = 0;
  int ident_level_ = 0;
  int ident_held_ = 0;
  bool ident_done_ = false;
  double ident_factor_ = 1;
  void advance_identification() noexcept;
  int decimation_ = 1;
  ForceBatchRecord batch_;
  rt::SpscRing<EdgeEvent, 1024> events_;
  rt::SpscRing<RevolutionRecord, 256> revolutions_;
  rt::SpscRing<ForceBatchRecord, 16> batches_;
  rt::SpscRing<FixedProgram, 4> programs_;
};

}  // namespace smc::edge
