// Cell benchmarks:
//   1. SMC I planning time per job (critical depth by time-domain simulation),
//      beside the time of one 1 s time-domain simulation of the same cut
//      measured in the same run (the planner's cost in "simulated cuts").
//   2. Configuration delivery to N edges (default 20 smc-edge processes on
//      loopback): time from publishing each edge's SupervisorConfig until
//      every edge reports it in force, beside the same for one edge.
//   3. The cell service's CPU while N edges run jobs and stream telemetry,
//      beside its idle CPU over the same window.
// 2 and 3 run twice, over plain DDS and under DDS Security (a PKI of its
// own from deploy/security/pki.sh; every process on its own identity, each
// edge confined to its mill's partition), and print the ratio (issue 16's
// goal: cell CPU with 20 streaming edges <= 2x plain).
//
//   build/release/bin/smc-bench-cell [--edges N] [--plans N] [--window-s S]

#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "secure_dds.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc/transport/document.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

using Clock = std::chrono::steady_clock;
namespace store = smc::cell::store;
namespace tr = smc::transport;

namespace {

std::string src(const std::string& rel) { return std::string(SMC_SOURCE_DIR) + "/" + rel; }
double secs(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

void bench_planning(int plans) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-bench-plan-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto db = store::Store::open((dir / "cell.db").string());
  store::seed_demo(db);
  smc::config::SupervisorConfig defaults;
  smc::documents::load(src("cell/configs/defaults.textproto"), defaults);
  smc::cell::Planner planner(src("cell/grafcets"), defaults);
  smc::config::Job spec;
  spec.set_part_id("bracket-tl");
  const auto job = db.submit_job(spec);
  const auto part = *db.part(job.spec.part_id());
  const auto tool = *db.tool(job.spec.tool_id());
  smc::cell::PlanInputs in{job, part, tool,
                           db.find_models("mill-1", tool.id, part.material_id, part.id),
                           *db.machine("mill-1")};
  const auto sel = smc::cell::select_variant(in);
  if (!sel.milling) {
    std::printf("SMC I planning: %s has no validated milling model for mill-1 (%s)\n",
                part.id.c_str(), std::string(store::variant_name(sel.variant)).c_str());
    std::filesystem::remove_all(dir);
    return;
  }
  double total = 0, crit = 0;
  for (int i = 0; i < plans; ++i) {
    const auto p = planner.plan(in, sel);
    total += p.planning_s;
    crit = p.critical_depth_mm;
  }
  // Baseline: one second of the same cut, simulated once.
  const auto model = smc::machining::from_proto(sel.milling->milling);
  smc::machining::CutConditions cut;
  cut.spindle_rpm = job.spec.spindle_rpm();
  cut.depth_mm = 1.0;
  cut.feed_per_tooth_mm = job.spec.feedrate_mm_s() / (tool.teeth * cut.spindle_rpm / 60.0);
  smc::machining::BatchOptions bo;
  bo.duration_s = 1.0;
  const auto t0 = Clock::now();
  (void)smc::machining::simulate(model, cut, bo);
  const double one = secs(Clock::now() - t0);
  std::printf("SMC I planning (%s): %.3f s per job (critical depth %.3f mm), %d jobs\n",
              std::string(store::variant_name(sel.variant)).c_str(), total / plans, crit, plans);
  std::printf("  baseline: 1 s of the cut simulated in %.3f s; planning = %.1f x that\n", one,
              total / plans / one);
  std::filesystem::remove_all(dir);
}

// Starts n edges, then publishes a configuration to each and waits until all
// report it in force. Returns seconds.
// An edge process for mill-i, under `dds`.
std::unique_ptr<smc::test::ChildProcess> start_edge(int i, const std::string& partition,
                                                    const smc::test::SecureDds& dds) {
  const std::string m = "mill-" + std::to_string(i);
  return std::make_unique<smc::test::ChildProcess>(
      dds.child({smc::test::bin_path("smc-edge"), "--log-level", "warn", "run", "--machine", m,
                 "--domain", std::to_string(dds.domain()), "--partition", partition, "--paced",
                 "--no-realtime", "--mill-model", src("cell/models/paper_face_mill.textproto")},
                "edge-" + m));
}

double deliver(int n, const std::string& partition, bool print, const smc::test::SecureDds& dds) {
  std::vector<std::unique_ptr<smc::test::ChildProcess>> edges;
  for (int i = 1; i <= n; ++i) edges.push_back(start_edge(i, partition, dds));
  tr::Participant p(dds.participant(partition));
  tr::Topic<smc_data_Envelope> topic(p, smc::wire::kConfigTopic);
  tr::DocumentWriter writer(topic, {"smc.config.SupervisorConfig", 1}, /*per_machine=*/true);
  tr::Topic<smc_data_EdgeStatus> st_topic(p);
  tr::Reader<smc_data_EdgeStatus> status(st_topic);
  // Every edge up (its status seen) before the clock starts.
  std::map<std::string, std::string> msg;
  const auto up_deadline = Clock::now() + std::chrono::seconds(60);
  while (static_cast<int>(msg.size()) < n && Clock::now() < up_deadline) {
    status.take([&](const smc_data_EdgeStatus& s, const tr::SampleInfo& i) {
      if (i.valid_data) msg[smc::wire::get_string(s.machine_id)] = smc::wire::get_string(s.message);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // Each mill's configuration goes into its own partition, through its own writer.
  for (int i = 1; i <= n; ++i) {
    writer.writer_for("mill-" + std::to_string(i)).wait_for_readers(1, std::chrono::seconds(30));
  }
  auto cfg = smc::documents::load_supervisor_config(src("edge/configs/smc2.textproto"));
  const auto t0 = Clock::now();
  for (int i = 1; i <= n; ++i) {
    cfg.set_config_id("bench-" + std::to_string(i));
    cfg.mutable_machine()->set_machine_id("mill-" + std::to_string(i));
    writer.publish("mill-" + std::to_string(i), cfg.config_id(), cfg);
  }
  int in_force = 0;
  std::map<std::string, bool> done;
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (in_force < n && Clock::now() < deadline) {
    status.take([&](const smc_data_EdgeStatus& s, const tr::SampleInfo& i) {
      if (!i.valid_data) return;
      const std::string id = smc::wire::get_string(s.machine_id);
      if (!done[id] && smc::wire::get_string(s.message).find("in force") != std::string::npos) {
        done[id] = true;
        ++in_force;
      }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const double t = secs(Clock::now() - t0);
  if (print && in_force < n) std::printf("  only %d of %d edges confirmed\n", in_force, n);
  return in_force == n ? t : -1;
}

// CPU seconds (user + system) a process has used so far.
double cpu_seconds(pid_t pid) {
  std::FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r");
  if (f == nullptr) return -1;
  char buf[2048];
  const size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  buf[n] = '\0';
  // Fields after the command name: state is field 3; utime 14, stime 15.
  const char* p = std::strrchr(buf, ')');
  if (p == nullptr) return -1;
  unsigned long long utime = 0, stime = 0;
  int field = 2;
  for (const char* c = p + 1; *c != '\0'; ++c) {
    if (*c == ' ') {
      ++field;
      if (field == 14) utime = std::strtoull(c + 1, nullptr, 10);
      if (field == 15) {
        stime = std::strtoull(c + 1, nullptr, 10);
        break;
      }
    }
  }
  return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// The cell service's CPU while `n` edge processes run jobs and stream their
// telemetry at real speed, beside its CPU over the same window with no edge.
// Returns the cell's CPU share with n edges streaming.
double bench_stream(int n, double window_s, const smc::test::SecureDds& dds) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-bench-stream-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string db_path = (dir / "cell.db").string();
  {
    auto db = store::Store::open(db_path);
    store::seed_demo(db);
    const auto proto = *db.machine("mill-1");
    for (int i = 3; i <= n; ++i) {
      store::Machine m = proto;
      m.id = "mill-" + std::to_string(i);
      m.name = m.id;
      db.put_machine(m);
    }
  }
  const std::string partition = smc::test::unique_partition("stream");
  smc::test::ChildProcess cell(
      dds.child({smc::test::bin_path("smc-cell"), "--log-level", "warn", "serve", "--db", db_path,
                 "--domain", std::to_string(dds.domain()), "--partition", partition},
                "cell"));
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const double idle0 = cpu_seconds(cell.pid());
  std::this_thread::sleep_for(std::chrono::duration<double>(window_s));
  const double idle = cpu_seconds(cell.pid()) - idle0;
  std::vector<std::unique_ptr<smc::test::ChildProcess>> edges;
  for (int i = 1; i <= n; ++i) edges.push_back(start_edge(i, partition, dds));
  {
    auto db = store::Store::open(db_path, store::OpenMode::kExisting);
    smc::config::Job spec;
    spec.set_part_id("housing-js");  // SMC II: the cell also collects data to learn from
    for (int i = 0; i < n; ++i) db.submit_job(spec);
  }
  // Until every job runs, then the measured window.
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  for (;;) {
    auto db = store::Store::open(db_path, store::OpenMode::kExisting);
    if (static_cast<int>(db.jobs({.state = smc::config::JOB_RUNNING}).size()) == n) break;
    if (Clock::now() > deadline) {
      std::printf("  not every job started within 60 s\n");
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  double edges0 = 0;
  for (auto& e : edges) edges0 += cpu_seconds(e->pid());
  const double busy0 = cpu_seconds(cell.pid());
  std::this_thread::sleep_for(std::chrono::duration<double>(window_s));
  const double busy = cpu_seconds(cell.pid()) - busy0;
  double edges1 = 0;
  for (auto& e : edges) edges1 += cpu_seconds(e->pid());
  std::printf(
      "%s: cell CPU with %d edges streaming (each a job at real speed: ~25 force summaries "
      "and raw batches/s): %.1f %% of one core; idle: %.1f %%; one edge's own CPU: %.1f %%\n",
      dds.name(), n, 100 * busy / window_s, 100 * idle / window_s,
      100 * (edges1 - edges0) / n / window_s);
  edges.clear();
  std::filesystem::remove_all(dir);
  return busy / window_s;
}

}  // namespace

int main(int argc, char** argv) {
  int edges = 20, plans = 3;
  double window_s = 10;
  CLI::App app{
      "smc-bench-cell: SMC I planning time per job; configuration delivery to N edges and "
      "the cell\n"
      "service's CPU with N edges streaming, over plain DDS and under DDS Security (same run)."};
  app.add_option("--edges", edges, "smc-edge processes on loopback")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--plans", plans, "SMC I plans timed")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--window-s", window_s, "seconds over which the cell's CPU is measured")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (std::getenv("CYCLONEDDS_URI") == nullptr) {
    ::setenv("CYCLONEDDS_URI", ("file://" + src("deploy/cyclonedds/loopback.xml")).c_str(), 1);
  }
  bench_planning(plans);
  std::vector<std::string> machines;
  for (int i = 1; i <= edges; ++i) machines.push_back("mill-" + std::to_string(i));
  const smc::test::SecureDds plain;
  const smc::test::SecureDds secure(7, machines);
  double many_of[2] = {0, 0};
  for (const auto* dds : {&plain, &secure}) {
    const double one = deliver(1, smc::test::unique_partition("deliver1"), true, *dds);
    const double many = deliver(edges, smc::test::unique_partition("deliverN"), true, *dds);
    many_of[dds->secure() ? 1 : 0] = many;
    std::printf(
        "%s: configuration delivery (checked and in force): 1 edge %.0f ms; %d edges %.0f ms "
        "(%.1f x one edge)\n",
        dds->name(), 1000 * one, edges, 1000 * many, many / one);
  }
  const double cpu_plain = bench_stream(edges, window_s, plain);
  const double cpu_secure = bench_stream(edges, window_s, secure);
  std::printf(
      "DDS Security / plain: delivery to %d edges %.2f x; cell CPU with %d edges streaming "
      "%.2f x (goal <= 2 x)\n",
      edges, many_of[0] > 0 ? many_of[1] / many_of[0] : 0.0, edges,
      cpu_plain > 0 ? cpu_secure / cpu_plain : 0.0);
  return 0;
}
