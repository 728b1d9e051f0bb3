// Edge benchmarks:
//  - BM_TickModules/<config>: CPU time of one 0.5 ms tick of the edge core
//    with the configuration's modules and supervisor, the drive replaced by a
//    recorded SMC II cut played from memory (so only the edge's own work is
//    timed). Reported against the 500 us budget ("budget_pct": mean tick as
//    a share of the sample period; "worst_tick_us": the slowest tick seen,
//    which includes any preemption of this process) and against the
//    no-control core measured in the same run.
//  - BM_VirtualRun/<config>: a whole run with the simulated mill in virtual
//    time; "x_real_time" is machine seconds per wall-clock second.
//  - BM_ChatterRevolution/<rpm>/<estimate>: module E's work for one
//    revolution (its samples and its decision) at that speed, with S alone
//    (0) or with the vibration estimate and its spectral correction from a
//    wideband channel sampled once (1) or five times (5, as shipped) a
//    period;
//    "budget_pct": that work as a share of the revolution's duration.
//
//   build/release/bin/smc-bench-edge [--benchmark_filter=...]

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/modules.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc_config.pb.h"

using namespace smc::edge;

namespace {

smc::config::SupervisorConfig config(const std::string& name) {
  return smc::documents::load_supervisor_config(std::string(SMC_SOURCE_DIR) + "/edge/configs/" +
                                                name);
}

// Plays a recorded sequence of drive samples in a loop; costs next to nothing.
class MemoryDrive final : public Drive {
 public:
  explicit MemoryDrive(std::vector<DriveSample> samples) : samples_(std::move(samples)) {}
  void load(const FixedProgram&) override { next_ = 0; }
  Status step(double, DriveSample& out) noexcept override {
    out = samples_[next_];
    next_ = next_ + 1 == samples_.size() ? 0 : next_ + 1;
    out.program_done = false;
    return Status::kOk;
  }
  Status rewrite(const FixedProgram&, int) noexcept override { return Status::kOk; }
  double sample_period_s() const noexcept override { return 0.0005; }

 private:
  std::vector<DriveSample> samples_;
  size_t next_ = 0;
};

// The drive samples of an SMC II run (contact, chatter, suppression, passes).
const std::vector<DriveSample>& recorded() {
  static const std::vector<DriveSample> samples = [] {
    auto raw = config("smc2.textproto");
    EdgeConfig cfg = edge_config_from_proto(raw);
    SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
    EdgeCore core(cfg, mill);
    core.start();
    std::vector<DriveSample> out;
    EdgeEvent e;
    RevolutionRecord r;
    ForceBatchRecord b;
    for (int i = 0; i < 40000 && !core.done(); ++i) {  // the first 20 s
      core.tick();
      out.push_back(core.drive_sample());
      while (core.events().try_pop(e)) {
      }
      while (core.revolutions().try_pop(r)) {
      }
      while (core.batches().try_pop(b)) {
      }
    }
    return out;
  }();
  return samples;
}

void tick_modules(benchmark::State& state, const char* name) {
  auto raw = config(name);
  EdgeConfig cfg = edge_config_from_proto(raw);
  MemoryDrive drive(recorded());
  EdgeCore core(cfg, drive);
  core.start();
  EdgeEvent e;
  RevolutionRecord r;
  ForceBatchRecord b;
  // The slowest tick is the one at a revolution boundary (FFT, estimator,
  // controller): time every tick and keep the worst as well as the mean.
  double worst_ns = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    core.tick();
    const auto t1 = std::chrono::steady_clock::now();
    worst_ns = std::max(worst_ns, std::chrono::duration<double, std::nano>(t1 - t0).count());
    while (core.events().try_pop(e)) {
    }
    while (core.revolutions().try_pop(r)) {
    }
    while (core.batches().try_pop(b)) {
    }
  }
  // Mean time per tick as a share of the 500 us sample period.
  state.counters["budget_pct"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 500e-6 / 100.0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["worst_tick_us"] = worst_ns / 1000.0;
}

void virtual_run(benchmark::State& state, const char* name) {
  auto raw = config(name);
  EdgeConfig cfg = edge_config_from_proto(raw);
  double machine_s = 0;
  for (auto _ : state) {
    SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
    EdgeCore core(cfg, mill);
    core.start();
    RunOptions opts;
    opts.keep_samples = false;
    RunResult run = run_virtual(core, opts);
    machine_s += run.end_time_s;
    benchmark::DoNotOptimize(run.ticks);
  }
  state.counters["x_real_time"] = benchmark::Counter(machine_s, benchmark::Counter::kIsRate);
}

// One revolution of a cut with chatter at `rpm` through E: a tooth harmonic
// and a 737 Hz tone in F_z and in the wideband F_y. At 1194 rpm a revolution
// is 100.5 samples, so the estimate reads the revolution before through the
// fractional delay's taps; at 750 and 3000 rpm it falls on a sample.
// `estimate`: the wideband channel's samples a period (0: no estimate, S
// alone; 1: the loop's rate; 5: the shipped 10 kHz).
void chatter_revolution(benchmark::State& state) {
  const double rpm = static_cast<double>(state.range(0));
  const auto per_tick = static_cast<int>(state.range(1));
  EdgeParameters p = edge_config_from_proto(config("smc2.textproto")).params;
  if (per_tick == 0) p.vibration_mode_count = 0;
  p.vibration_samples_per_tick = std::max(per_tick, 1);
  AutomaticChatterDetector e;
  e.configure(p);
  Signals s;
  s.spindle_rpm = rpm;
  s.engagement = 1;
  const auto n = static_cast<int>(60.0 / rpm / p.sample_period_s);
  s.revolution_samples = n;
  constexpr double kPi = 3.14159265358979323846;
  uint64_t k = 0;
  for (auto _ : state) {
    for (int i = 0; i < n; ++i, ++k) {
      const double t = static_cast<double>(k) * p.sample_period_s;
      const double tooth = std::sin(2 * kPi * 4 * rpm / 60 * t);
      const double chatter = std::sin(2 * kPi * 737 * t);
      s.sample.f_z_n = 300 + 80 * tooth + 20 * chatter;
      s.sample.f_y_wide_n = 400 + 150 * tooth + 20 * chatter;
      if (per_tick > 1) {
        s.sample.wide_count = per_tick;
        for (int j = 0; j < per_tick; ++j) {
          const double u = t + (j + 1 - per_tick) * p.sample_period_s / per_tick;
          s.sample.f_y_wide_sub_n[j] =
              400 + 150 * std::sin(2 * kPi * 4 * rpm / 60 * u) + 20 * std::sin(2 * kPi * 737 * u);
        }
      }
      if (e.on_sample(s) != Status::kOk) state.SkipWithError("E refused the sample");
    }
    e.update(s);
    e.clear_outputs(s);
    benchmark::DoNotOptimize(s.chatter_vibration_ratio);
  }
  state.counters["budget_pct"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 60.0 / rpm / 100.0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK_CAPTURE(tick_modules, no_control, "no_control.textproto");
BENCHMARK_CAPTURE(tick_modules, smc1, "smc1.textproto");
BENCHMARK_CAPTURE(tick_modules, smc2, "smc2.textproto");
BENCHMARK_CAPTURE(virtual_run, smc2, "smc2.textproto")->Unit(benchmark::kSecond)->Iterations(2);

BENCHMARK(chatter_revolution)
    ->ArgNames({"rpm", "estimate"})
    ->ArgsProduct({{750, 1194, 3000}, {0, 1, 5}})
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
