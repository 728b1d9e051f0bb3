// smc-dashboard-fake-mill: TEST TOOL. Publishes what N edges and the cell
// would publish, at wall-clock pace, and obeys operator commands (see
// fake_mill.hpp). For dashboard tests, benchmarks and front-end work until
// `smc-cell serve` and `smc-edge run` take its place.

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>

#include "fake_mill.hpp"
#include "smc/common/log.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "smc-dashboard-fake-mill: TEST TOOL. Publishes force summaries and batches, supervisor\n"
      "situations (the shipped Grafcets run by smc_grafcet), edge status, job progress, chatter\n"
      "events, SupervisorConfig, PartProgram and JobStatus documents for N simulated mills, and\n"
      "obeys OperatorCommands (feed hold on/off, chatter signal)."};
  smc::dashboard::testing::FakeCellOptions o;
  o.grafcet_dir = SMC_GRAFCET_DIR;
  app.add_option("--mills", o.mills, "number of mills (1-100)")->capture_default_str();
  app.add_option("--prefix", o.prefix, "machine id prefix; mills are PREFIX1..PREFIXN")
      ->capture_default_str();
  app.add_option("--domain", o.domain_id, "DDS domain id")->capture_default_str();
  app.add_option("--partition", o.partition, "DDS partition");
  app.add_option("--grafcet-dir", o.grafcet_dir, "folder with smc1.grafcet and smc2.grafcet")
      ->capture_default_str();
  app.add_option("--seed", o.seed, "noise seed")->capture_default_str();
  app.add_option("--duration", o.duration_s, "seconds to run (0: until SIGINT/SIGTERM)")
      ->capture_default_str();
  app.add_option("--part-length", o.part_length_mm, "part length along the feed, mm")
      ->capture_default_str();
  app.add_flag("--all-smc2", o.all_smc2, "every mill runs SMC II (default: odd mills only)");
  CLI11_PARSE(app, argc, argv);
  smc::log::init(smc::log::Options{.name = "smc-dashboard-fake-mill"});
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    return smc::dashboard::testing::run_fake_cell(o, g_stop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-dashboard-fake-mill: error: %s\n", e.what());
    return 1;
  }
}
