// Benchmarks of smc_machining on the paper's case (and the Insperger-Stepan
// 1-DOF model for the lobes). Figures of merit:
//   sim_s_per_s   simulated seconds per CPU second (goal >= 200 at a 1e-5 s step)
//   speeds_per_s  lobe-diagram speeds per CPU second (goal: 200 speeds < 1 s)

#include <benchmark/benchmark.h>

#include <numbers>
#include <vector>

#include "smc/machining/lobes.hpp"
#include "smc/machining/paper_case.hpp"
#include "smc/machining/simulator.hpp"
#include "smc/machining/tds.hpp"

namespace mc = smc::machining;

namespace {

// One simulated second of the stepping simulator, 0.5 ms samples, 1e-5 s
// internal step, cutting the whole time (a long part).
void BM_SimulatorStep_PaperCase(benchmark::State& state) {
  mc::MillingModel m = mc::paper_case();
  m.workpiece.length_mm = 1e6;
  const double depth = static_cast<double>(state.range(0)) / 10;
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 0;
  mc::MillSimulator sim(m, o);
  mc::Sample s;
  for (auto _ : state) {
    for (int k = 0; k < 2000; ++k) sim.step({10, 1500, depth}, s);
    benchmark::DoNotOptimize(s.fy_n);
  }
  state.counters["sim_s_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["internal_step_s"] = sim.internal_step_s();
}
BENCHMARK(BM_SimulatorStep_PaperCase)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);

// The same with one internal step per call (what a caller that filters the
// force itself does), forces of the last step.
void BM_SimulatorInternalStepCalls_PaperCase(benchmark::State& state) {
  mc::MillingModel m = mc::paper_case();
  m.workpiece.length_mm = 1e6;
  mc::SimulatorOptions o;
  o.sample_period_s = 1e-5;
  o.forces_at_sample_instant = false;
  mc::MillSimulator sim(m, o);
  mc::Sample s;
  for (auto _ : state) {
    for (int k = 0; k < 100000; ++k) sim.step({10, 1500, 1.0}, s);
    benchmark::DoNotOptimize(s.fy_n);
  }
  state.counters["sim_s_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulatorInternalStepCalls_PaperCase)->Unit(benchmark::kMillisecond);

// As the edge's simulated mill calls it: one call per 0.5 ms sample, the
// force of each of its 50 internal steps written out for the sensor filters.
void BM_SimulatorTraced_PaperCase(benchmark::State& state) {
  mc::MillingModel m = mc::paper_case();
  m.workpiece.length_mm = 1e6;
  mc::SimulatorOptions o;
  o.forces_at_sample_instant = false;
  mc::MillSimulator sim(m, o);
  std::vector<double> fx(static_cast<std::size_t>(sim.steps_per_sample()));
  std::vector<double> fy(fx.size()), fz(fx.size());
  const mc::StepForceTrace trace{fx.data(), fy.data(), fz.data()};
  mc::Sample s;
  for (auto _ : state) {
    for (int k = 0; k < 2000; ++k) sim.step({10, 1500, 1.0}, s, trace);
    benchmark::DoNotOptimize(fy.data());
  }
  state.counters["sim_s_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulatorTraced_PaperCase)->Unit(benchmark::kMillisecond);

// One simulated second of a batch run (steady cut, no records).
void BM_Batch_PaperCase(benchmark::State& state) {
  const mc::MillingModel m = mc::paper_case();
  mc::BatchOptions o;
  o.duration_s = 1.0;
  o.record_every_s = 0;
  for (auto _ : state) {
    const mc::BatchResult r = mc::simulate(m, {1500, 0.1, 1.0}, o);
    benchmark::DoNotOptimize(r.mean_power_w);
  }
  state.counters["sim_s_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Batch_PaperCase)->Unit(benchmark::kMillisecond);

// The paper's method: critical depth at 1500 rpm by bisection over depth
// with time-domain runs (relative tolerance 1e-3).
void BM_CriticalDepthTds_PaperCase(benchmark::State& state) {
  const mc::MillingModel m = mc::paper_case();
  double d = 0;
  std::size_t runs = 0;
  for (auto _ : state) {
    const mc::TdsSearchResult r = mc::critical_depth_tds(m, 1500, 0.1);
    d = r.critical_depth_mm;
    runs = r.probes.size();
  }
  state.counters["critical_depth_mm"] = d;
  state.counters["runs"] = static_cast<double>(runs);
}
BENCHMARK(BM_CriticalDepthTds_PaperCase)->Unit(benchmark::kMillisecond);

void BM_CriticalDepthSdm_PaperCase(benchmark::State& state) {
  const mc::MillingModel m = mc::paper_case();
  double d = 0;
  for (auto _ : state) d = mc::critical_depth_sdm(m, 1500, 0.1).critical_depth_mm;
  state.counters["critical_depth_mm"] = d;
}
BENCHMARK(BM_CriticalDepthSdm_PaperCase)->Unit(benchmark::kMillisecond);

// A 200-speed lobe diagram of the paper's case, 1000-3000 rpm.
void BM_Lobes200_PaperCase(benchmark::State& state) {
  const mc::MillingModel m = mc::paper_case();
  mc::LobeOptions o;
  o.rpm_min = 1000;
  o.rpm_max = 3000;
  o.speeds = 200;
  o.feed_per_tooth_mm = 0.1;
  for (auto _ : state) {
    const auto lobes = mc::stability_lobes(m, o);
    benchmark::DoNotOptimize(lobes.data());
  }
  state.counters["speeds_per_s"] = benchmark::Counter(
      200.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Lobes200_PaperCase)->Unit(benchmark::kMillisecond);

// A 200-speed diagram of Insperger & Stepan's 1-DOF down-milling example
// (a/D = 0.05, 5000-25000 rpm).
void BM_Lobes200_InspergerDownMilling(benchmark::State& state) {
  mc::MillingModel m;
  m.name = "insperger_stepan_1dof";
  m.cutter = mc::Cutter{2, 10.0, 0.0};
  m.workpiece = mc::Workpiece{1.0, -9.5, 100.0, true};
  m.law = mc::LinearLaw{600.0, 200.0, 0.0};
  const double wn = 2 * std::numbers::pi * 922.0;
  m.structure.tool_x = {mc::Mode{wn, 0.011, 0.03993 * wn * wn / 1000.0}};
  mc::LobeOptions o;
  o.rpm_min = 5000;
  o.rpm_max = 25000;
  o.speeds = 200;
  o.feed_per_tooth_mm = 0.05;
  o.sdm.max_depth_mm = 10;
  for (auto _ : state) {
    const auto lobes = mc::stability_lobes(m, o);
    benchmark::DoNotOptimize(lobes.data());
  }
  state.counters["speeds_per_s"] = benchmark::Counter(
      200.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Lobes200_InspergerDownMilling)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
