// smc-edge hal-samples: is the edge getting every servo period of a LinuxCNC
// machine? Reads the sampler stream the LinuxCNC drive reads and reports
// continuity, for machine builders and the tests.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "../drive/linuxcnc/hal_stream.hpp"
#include "commands.hpp"

namespace smc::edge::cli {

void add_hal(CLI::App& app) {
  struct Args {
    std::string component = "smc-edge-probe";
    long count = 10000;
    double timeout_s = 30;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "hal-samples",
      "Read N records of the LinuxCNC servo thread through the sampler stream the LinuxCNC\n"
      "drive uses (deploy/linuxcnc/smc-edge.hal) and report lost and repeated records, the\n"
      "largest backlog, the path travelled and the spindle's turns, as JSON. Exit 0 when no\n"
      "record was lost or repeated, 1 otherwise, 2 when HAL or the sampler is not there.\n"
      "Run it as LinuxCNC's user: deploy/linuxcnc/run.sh exec smc-edge hal-samples");
  sub->add_option("--component", args->component, "HAL component name to join as")
      ->capture_default_str();
  sub->add_option("--count", args->count, "Records to read")
      ->check(CLI::Range(1L, 100000000L))
      ->capture_default_str();
  sub->add_option("--timeout", args->timeout_s, "Give up after this many seconds")
      ->capture_default_str();
  sub->callback([args] {
    std::unique_ptr<linuxcnc::HalSampleStream> s;
    try {
      s = std::make_unique<linuxcnc::HalSampleStream>(args->component);
    } catch (const std::runtime_error& e) {
      throw Failure(2, e.what());
    }
    linuxcnc::HalRecord r, first;
    int backlog_max = 0;
    double x_min = INFINITY, x_max = -INFINITY;
    const auto t0 = std::chrono::steady_clock::now();
    const auto deadline = t0 + std::chrono::duration<double>(args->timeout_s);
    while (static_cast<long>(s->records()) < args->count) {
      backlog_max = std::max(backlog_max, s->backlog());
      if (!s->read(r)) {
        if (std::chrono::steady_clock::now() > deadline) break;
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        continue;
      }
      if (s->records() == 1) first = r;
      x_min = std::min(x_min, r.x_mm);
      x_max = std::max(x_max, r.x_mm);
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool complete = static_cast<long>(s->records()) >= args->count;
    std::printf(
        "{\"records\": %llu, \"lost\": %llu, \"repeated\": %llu, \"overruns\": %d, "
        "\"max_backlog\": %d, \"wall_s\": %.3f, \"x_min_mm\": %.4f, \"x_max_mm\": %.4f, "
        "\"spindle_revs\": %.3f, \"complete\": %s}\n",
        static_cast<unsigned long long>(s->records()), static_cast<unsigned long long>(s->lost()),
        static_cast<unsigned long long>(s->repeated()), s->overruns(), backlog_max, wall,
        s->records() > 0 ? x_min : 0.0, s->records() > 0 ? x_max : 0.0,
        s->records() > 0 ? r.spindle_revs - first.spindle_revs : 0.0, complete ? "true" : "false");
    if (!complete) throw Failure(1, "timed out after " + std::to_string(args->timeout_s) + " s");
    if (s->lost() > 0 || s->repeated() > 0) {
      throw Failure(1, "records lost or repeated: the edge would not see every servo period");
    }
  });
}

}  // namespace smc::edge::cli
