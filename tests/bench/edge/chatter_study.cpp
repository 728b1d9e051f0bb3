// Module E on stable and unstable cuts: false-alarm rate and detection delay.
//
//   build/release/bin/smc-bench-chatter-detector [--seeds N]
//
// Runs the shipped SMC II configuration on the simulated mill with one pass
// of each depth and several sensor-noise seeds. Stable cuts (no chatter onset
// in the mill's own vibration) give the false-alarm figures: revolutions in
// the cut whose statistic exceeded the threshold, and confirmed detections.
// Unstable cuts give the delay from the onset (found from the simulated
// vibration, independently of E) to E's detection.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc_config.pb.h"

using namespace smc::edge;

int main(int argc, char** argv) {
  int seeds = 4;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--seeds") == 0) seeds = std::atoi(argv[i + 1]);
  }
  const auto base = smc::documents::load_supervisor_config(std::string(SMC_SOURCE_DIR) +
                                                           "/edge/configs/smc2.textproto");
  std::printf(
      "module E: threshold %.2f on the non-harmonic share of F_z energy, %u revolutions "
      "to confirm, band %.0f-%.0f Hz, guard +-%.0f Hz, noise %.1f N rms\n\n",
      base.operation().chatter_threshold(), base.operation().chatter_confirm_revolutions(),
      base.operation().chatter_band_low_hz(), base.operation().chatter_band_high_hz(),
      base.operation().harmonic_guard_hz(), base.simulation().noise_rms_n());
  std::printf("%8s %5s %8s %12s %12s %10s %10s %10s\n", "depth_mm", "seed", "stable", "cut_revs",
              "exceedances", "detected", "onset_s", "delay_ms");
  uint64_t stable_revs = 0, stable_exceed = 0, stable_false = 0;
  double stable_max = 0;
  std::vector<double> delays;
  int missed = 0;
  for (double depth : {0.5, 0.8, 1.0, 1.2, 1.6, 2.0, 2.5}) {
    for (int seed = 1; seed <= seeds; ++seed) {
      auto raw = base;
      raw.mutable_program()->mutable_passes(0)->set_depth_mm(depth);
      raw.mutable_program()->set_total_depth_mm(depth);
      raw.mutable_simulation()->set_seed(static_cast<uint64_t>(seed));
      EdgeConfig cfg = edge_config_from_proto(raw);
      SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
      EdgeCore core(cfg, mill);
      core.start();
      RunOptions opts;
      opts.max_time_s = 60;
      RunResult run = run_virtual(core, opts);
      const auto s = summarize(core, run);
      const double first_detection = s.chatter_detected_s();
      uint64_t revs = 0, exceed = 0;
      double max_ratio = 0;
      for (const auto& r : run.revolutions) {
        if ((r.active & bit(ModuleId::E)) == 0 || !r.contact) continue;
        if (first_detection >= 0 && r.t_s > first_detection) break;
        ++revs;
        if (r.chatter_ratio > cfg.params.chatter_threshold) ++exceed;
        if (first_detection < 0) max_ratio = std::max(max_ratio, r.chatter_ratio);
      }
      const bool stable = s.chatter_onset_s() < 0;
      double delay_ms = -1;
      if (stable) {
        stable_max = std::max(stable_max, max_ratio);
        stable_revs += revs;
        stable_exceed += exceed;
        stable_false += first_detection >= 0 ? 1 : 0;
      } else if (first_detection >= 0) {
        delay_ms = 1000 * (first_detection - s.chatter_onset_s());
        delays.push_back(delay_ms);
      } else {
        ++missed;
      }
      std::printf("%8.1f %5d %8s %12llu %12llu %10s %10.2f %10.0f\n", depth, seed,
                  stable ? "yes" : "no", static_cast<unsigned long long>(revs),
                  static_cast<unsigned long long>(exceed), first_detection >= 0 ? "yes" : "no",
                  s.chatter_onset_s(), delay_ms);
    }
  }
  std::printf(
      "\nstable cuts: %llu revolutions in the cut, %llu above threshold (%.2f %% per "
      "revolution; largest statistic %.3f), %llu confirmed false detections\n",
      static_cast<unsigned long long>(stable_revs), static_cast<unsigned long long>(stable_exceed),
      stable_revs ? 100.0 * static_cast<double>(stable_exceed) / static_cast<double>(stable_revs)
                  : 0.0,
      stable_max, static_cast<unsigned long long>(stable_false));
  if (!delays.empty()) {
    double sum = 0, worst = 0;
    for (double d : delays) {
      sum += d;
      worst = std::max(worst, d);
    }
    std::printf(
        "unstable cuts: %zu detected, %d missed; delay from onset mean %.0f ms, worst "
        "%.0f ms (one revolution = %.0f ms)\n",
        delays.size(), missed, sum / static_cast<double>(delays.size()), worst,
        1000 * base.operation().slow_period_s());
  }
  return 0;
}
