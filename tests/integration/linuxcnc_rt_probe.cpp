// smc-linuxcnc-rt-probe CONFIG SECONDS PROGRAM_DIR
//
// The edge's loop on LinuxCNC under an allocation guard: the core with the
// LinuxCNC drive, one tick per servo record (wait, read, modules,
// supervisors, feed pins, heartbeat, and a rewrite's or a speed change's
// hand-over request) for
// SECONDS of machine time or to the program's end. Prints one JSON object
// with the ticks run and the operator-new calls the loop thread made in
// them (which must be 0). Run as LinuxCNC's user (deploy/linuxcnc/run.sh
// exec) with the virtual dynamometer loaded; linuxcnc_test.cpp does.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>

#include "alloc_counter.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/linuxcnc_drive.hpp"
#include "smc_config.pb.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: smc-linuxcnc-rt-probe CONFIG SECONDS PROGRAM_DIR\n");
    return 2;
  }
  try {
    const auto raw = smc::documents::load_supervisor_config(argv[1]);
    const smc::edge::EdgeConfig cfg = smc::edge::edge_config_from_proto(raw);
    smc::edge::LinuxCncDriveOptions lo;
    lo.machine_id = "smc-rt-probe";
    lo.program_dir = argv[3];
    smc::edge::LinuxCncDrive drive(raw, cfg.params.sample_period_s, lo);
    smc::edge::EdgeCore core(cfg, drive);
    core.start();
    const auto ticks_max =
        static_cast<std::uint64_t>(std::atof(argv[2]) / cfg.params.sample_period_s);
    std::uint64_t ticks = 0, allocations = 0;
    double broken_s = -1, broken_drop = 0, broken_rpm = 0, contact_s = -1;
    {
      smc::test::ForbidAllocations guard;
      for (; ticks < ticks_max && !core.done(); ++ticks) {
        (void)drive.wait_sample();
        core.tick(false);
        const auto& sig = core.signals();
        if (contact_s < 0 && sig.contact) contact_s = sig.sample.t_s;
        if (broken_s < 0 && sig.tool_broken) {
          broken_s = sig.sample.t_s;
          broken_drop = sig.breakage_drop;
          broken_rpm = sig.spindle_rpm;
        }
      }
      allocations = guard.violations();
    }
    // "rewrites": the program's revisions (a rewrite or a speed change);
    // "rpm": the spindle's measured speed at the end; "tool_broken": N's
    // latch (1: a breakage was detected, the drive lifted the tool).
    std::printf(
        "{\"ticks\": %llu, \"allocations\": %llu, \"rewrites\": %u, \"lost\": %llu, "
        "\"rpm\": %.0f, \"tool_broken\": %d, \"fault\": \"%s\", \"contact_s\": %.4f, "
        "\"broken_s\": %.4f, \"broken_drop\": %.3f, \"broken_rpm\": %.0f}\n",
        static_cast<unsigned long long>(ticks), static_cast<unsigned long long>(allocations),
        core.program().revision, static_cast<unsigned long long>(drive.lost_samples()),
        core.drive_sample().spindle_rpm, core.signals().tool_broken ? 1 : 0, drive.fault().c_str(),
        contact_s, broken_s, broken_drop, broken_rpm);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-linuxcnc-rt-probe: %s\n", e.what());
    return 1;
  }
}
