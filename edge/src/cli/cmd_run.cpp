// smc-edge run: the edge process of one mill on DDS.

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <string>
#include <vector>

#include "commands.hpp"
#include "smc/edge/service.hpp"
#include "smc_config.pb.h"

namespace smc::edge::cli {

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }
}  // namespace

void add_run(CLI::App& app) {
  auto opt = std::make_shared<ServiceOptions>();
  auto lease_ms = std::make_shared<int>(2000);
  auto no_rt = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand(
      "run",
      "Run the edge of one mill on DDS: take configurations and jobs from the cell, run each\n"
      "job in the 2 kHz real-time loop on the simulated mill (or on LinuxCNC: --drive\n"
      "linuxcnc), publish force, chatter, supervisor state, status and progress. Stops\n"
      "cleanly on SIGINT or SIGTERM.");
  sub->add_option("--machine", opt->machine_id, "Machine id (the cell addresses this edge by it)")
      ->required();
  sub->add_option("--domain", opt->domain_id, "DDS domain id")->capture_default_str();
  sub->add_option("--partition", opt->partition,
                  "the cell's DDS partition P (isolates a cell); this edge publishes and reads "
                  "only in P/machine/<--machine>");
  sub->add_option("--lease-ms", *lease_ms, "Liveliness lease of the status topic")
      ->capture_default_str()
      ->check(CLI::Range(100, 600000));
  sub->add_option("--speedup", opt->speedup,
                  "Machine seconds per wall second (1 = real time; tests and demos go faster)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 100.0));
  sub->add_option("--batch-decimation", opt->batch_decimation,
                  "Publish every n-th raw force sample")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  sub->add_option("--mill-model", opt->mill_model_file,
                  "The simulated mill's own milling model (default: the configuration's); the\n"
                  "edge's modules keep the configuration's models")
      ->check(CLI::ExistingFile);
  sub->add_flag("--no-realtime", *no_rt, "Do not ask for SCHED_FIFO and mlockall");
  sub->add_option("--drive", opt->drive,
                  "The machine: sim (the simulated mill) or linuxcnc (the LinuxCNC running on\n"
                  "this host with deploy/linuxcnc/smc-edge.hal; its servo thread paces the loop;\n"
                  "run as LinuxCNC's user: deploy/linuxcnc/run.sh exec smc-edge run ...)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "linuxcnc"}));
  sub->add_option("--program-dir", opt->program_dir,
                  "Where the G-code handed to LinuxCNC is written (--drive linuxcnc)")
      ->capture_default_str();
  sub->add_option("--state-file", opt->state_file,
                  "Journal of the job attempts this edge started, kept across restarts: one\n"
                  "started by an earlier run is reported interrupted, never cut again");
  sub->add_flag("--paced", opt->paced,
                "Run the simulated mill paced to the wall clock instead of in the real-time loop\n"
                "(no deadlines, no overrun holds; implied by --speedup other than 1)");
  auto breaks = std::make_shared<std::vector<std::string>>();
  sub->add_option("--break-tooth", *breaks,
                  "Simulated mill only: tooth T breaks S s into every job, T@S or T@S:MM\n"
                  "(repeatable), to see module N stop a job (SMC II+)");
  auto overrun_ms = std::make_shared<double>(2.0);
  sub->add_option("--overrun-ms", *overrun_ms,
                  "A real-time tick this late is an overrun and holds the feed")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  sub->callback([opt, lease_ms, no_rt, overrun_ms, breaks] {
    if (!breaks->empty() && opt->drive != "sim") {
      throw Failure(2, "--break-tooth: only the simulated mill can break a tooth on request");
    }
    smc::config::SimulatedMill sim;
    for (const auto& spec : *breaks) add_tooth_break(spec, sim);
    for (const auto& b : sim.tooth_breaks())
      opt->tooth_breaks.push_back({b.tooth(), b.at_s(), b.edge_loss_mm()});
    if (opt->drive == "linuxcnc" && opt->speedup != 1.0) {
      throw Failure(2, "--speedup: LinuxCNC runs in real time (its servo thread paces the loop)");
    }
#if !SMC_HAVE_LINUXCNC
    if (opt->drive == "linuxcnc") {
      throw Failure(2,
                    "--drive linuxcnc: this smc-edge was built without LinuxCNC (install "
                    "linuxcnc-uspace-dev with deploy/setup.sh and build again)");
    }
#endif
    opt->lease = std::chrono::milliseconds(*lease_ms);
    opt->realtime = !*no_rt;
    opt->overrun_threshold = std::chrono::microseconds(static_cast<int64_t>(*overrun_ms * 1000));
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    EdgeService service(*opt);
    const int rc = service.run(g_stop);
    if (rc != 0) throw Failure(rc, "edge stopped with errors");
  });
}

}  // namespace smc::edge::cli
