// smc-bench-dashboard: end-to-end latency from a force summary's write on DDS
// to its arrival at push-stream clients of smc-dashboard, and the dashboard's
// CPU, with 10 mills streaming at 1500 rpm (a ForceSummary and a ForceBatch
// of 80 samples per mill every 40 ms, a SupervisorSituation per mill every
// second).
//
// Baseline in the same run: the same summaries through DDS alone, one hop to
// another process and back (smc-transport-echo, the transport tests' echo),
// halved: what a DDS subscriber in another process sees, so the dashboard's
// share is the difference.
// The dashboard runs as its own process (bin/smc-dashboard) so its CPU is
// measured alone, from /proc/PID/stat.
//
//   smc-bench-dashboard [--mills 10] [--seconds 10] [--cell-clients 2] [--mill-clients 2]
//
// Browser arrival (the page's EventSource handler) is measured by
// smc-bench-dashboard-browser (tests/bench/dashboard/browser_latency.mjs).
// The whole measurement runs twice: over plain DDS, then under DDS Security
// (a PKI of its own: the dashboard on its identity, the publishers and the
// echo on the cell's), and prints what security adds.

#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "http_client.hpp"
#include "secure_dds.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
namespace tr = smc::transport;

constexpr std::uint32_t kRevolutionsKept = 1 << 16;

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// Write time of each (mill, revolution), shared by the publisher and readers.
class WriteTimes {
 public:
  explicit WriteTimes(int mills) : t_(static_cast<size_t>(mills) * kRevolutionsKept) {}
  void set(int mill, std::uint32_t rev, int64_t t) { slot(mill, rev).store(t); }
  int64_t get(int mill, std::uint32_t rev) { return slot(mill, rev).load(); }

 private:
  std::atomic<int64_t>& slot(int mill, std::uint32_t rev) {
    return t_[static_cast<size_t>(mill) * kRevolutionsKept + (rev % kRevolutionsKept)];
  }
  std::vector<std::atomic<int64_t>> t_;
};

struct Samples {
  std::mutex mu;
  std::vector<double> ms;
  std::atomic<bool> recording{false};
  void add(double v) {
    if (!recording.load()) return;
    std::lock_guard lock(mu);
    ms.push_back(v);
  }
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

int mill_index(const std::string& id) { return std::stoi(id.substr(id.rfind('-') + 1)) - 1; }

// CPU seconds (user + system) of a process.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  std::istringstream rest(s.substr(s.rfind(')') + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  for (int i = 3; i <= 15; ++i) {
    rest >> field;
    if (i == 14) utime = std::stoull(field);
    if (i == 15) stime = std::stoull(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

uint16_t free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// Pulls "key":value out of a flat JSON object (the summary event).
std::string json_value(const std::string& s, const std::string& key) {
  const std::string k = "\"" + key + "\":";
  const size_t p = s.find(k);
  if (p == std::string::npos) return {};
  size_t b = p + k.size();
  if (s[b] == '"') {
    const size_t e = s.find('"', b + 1);
    return s.substr(b + 1, e - b - 1);
  }
  const size_t e = s.find_first_of(",}", b);
  return s.substr(b, e - b);
}

}  // namespace

// One measurement over `dds` (plain DDS, or DDS Security with the
// dashboard and the echo on their own identities); returns the cell-view
// clients' latencies (ms).
static std::vector<double> measure(const smc::test::SecureDds& dds, int mills, int seconds,
                                   int cell_clients, int mill_clients) {
  const std::string partition = smc::test::unique_partition("bench-dashboard");
  const uint16_t port = free_port();
  smc::test::ChildProcess dash(dds.child(
      {smc::test::bin_path("smc-dashboard"), "--http", "127.0.0.1:" + std::to_string(port),
       "--domain", std::to_string(dds.domain()), "--partition", partition, "--log-level", "warn"},
      "dashboard"));
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  if (!dash.wait_for_line("smc-dashboard: listening on " + url)) {
    std::fprintf(stderr, "smc-dashboard did not start\n");
    std::exit(1);
  }

  tr::Participant participant(dds.participant(partition));
  tr::Topic<smc_data_ForceSummary> summary_topic(participant);
  tr::Topic<smc_data_ForceBatch> batch_topic(participant);
  tr::Topic<smc_data_SupervisorSituation> situation_topic(participant);
  tr::Writer<smc_data_ForceSummary> summaries(summary_topic);
  tr::Writer<smc_data_ForceBatch> batches(batch_topic);
  tr::Writer<smc_data_SupervisorSituation> situations(situation_topic);

  // Baseline: DDS alone, through the echo process (partition E.req -> E.rep).
  const std::string echo_partition = partition + "-echo";
  smc::test::ChildProcess echo(
      dds.child({smc::test::bin_path("smc-transport-echo"), "--partition", echo_partition,
                 "--domain", std::to_string(dds.domain()), "--idle-s", "30"},
                "cell"));
  if (!echo.wait_for_line("ready")) {
    std::fprintf(stderr, "smc-transport-echo did not start (build the tests)\n");
    std::exit(1);
  }
  tr::Participant req_participant(dds.participant(echo_partition + ".req"));
  tr::Participant base_participant(dds.participant(echo_partition + ".rep"));
  tr::Topic<smc_data_ForceSummary> req_topic(req_participant);
  tr::Writer<smc_data_ForceSummary> req_writer(req_topic);
  tr::Topic<smc_data_ForceSummary> base_topic(base_participant);
  tr::Reader<smc_data_ForceSummary> base_reader(base_topic);

  WriteTimes written(mills);
  Samples dds_only;
  std::vector<std::unique_ptr<Samples>> client_samples;
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;

  threads.emplace_back([&] {
    tr::WaitSet ws(base_participant);
    ws.attach(base_reader, 1);
    std::vector<int64_t> fired;
    while (!stop.load()) {
      ws.wait(100ms, fired);
      const int64_t t = now_ns();
      base_reader.take([&](const smc_data_ForceSummary& s, const tr::SampleInfo& i) {
        if (!i.valid_data) return;
        const int m = mill_index(smc::wire::get_string(s.machine_id));
        dds_only.add(static_cast<double>(t - written.get(m, s.revolution)) * 0.5e-6);
      });
    }
  });

  // Stream clients: "cell view" (every mill, no raw) and "mill view" (one
  // mill with its raw batches), as the page opens them.
  std::vector<std::unique_ptr<smc::test::SseClient>> clients;
  for (int c = 0; c < cell_clients + mill_clients; ++c) {
    const bool cell = c < cell_clients;
    const std::string target =
        cell ? "/api/stream"
             : "/api/stream?raw=1&mill=mill-" + std::to_string(c - cell_clients + 1);
    clients.push_back(std::make_unique<smc::test::SseClient>(port, target));
    client_samples.push_back(std::make_unique<Samples>());
  }
  for (size_t c = 0; c < clients.size(); ++c) {
    threads.emplace_back([&, c] {
      while (!stop.load()) {
        auto e = clients[c]->next(Clock::now() + 200ms);
        if (!e || e->event != "summary") continue;
        const int64_t t = now_ns();
        const int m = mill_index(json_value(e->data, "machine_id"));
        const auto rev = static_cast<std::uint32_t>(std::stoul(json_value(e->data, "revolution")));
        client_samples[c]->add(static_cast<double>(t - written.get(m, rev)) * 1e-6);
      }
    });
  }

  // The mills: one revolution per 40 ms each, spread evenly over the period.
  std::atomic<uint64_t> published{0};
  threads.emplace_back([&] {
    const auto period = 40ms;
    const auto slot = std::chrono::duration_cast<Clock::duration>(period) / mills;
    auto next = Clock::now();
    std::uint32_t rev = 0;
    while (!stop.load()) {
      ++rev;
      for (int m = 0; m < mills && !stop.load(); ++m) {
        next += slot;
        std::this_thread::sleep_until(next);
        const std::string id = "mill-" + std::to_string(m + 1);
        smc_data_ForceSummary s{};
        smc::wire::set_string(s.machine_id, id);
        s.revolution = rev;
        s.machine_time_ns = static_cast<uint64_t>(now_ns());
        s.f_y_peak_n = 180.f + static_cast<float>(rev % 20);
        s.f_ref_n = 190.f;
        s.pass_count = 2;
        s.in_contact = true;
        written.set(m, rev, now_ns());
        summaries.write(s);
        req_writer.write(s);
        smc_data_ForceBatch b{};
        smc::wire::set_string(b.machine_id, id);
        b.first_sample_time_ns = s.machine_time_ns - 40000000ULL;
        b.sample_period_ns = 500000;
        b.decimation = 1;
        b.count = 80;
        for (int k = 0; k < 80; ++k) {
          b.f_y_n[k] = -100.f - static_cast<float>(k);
          b.f_z_n[k] = 40.f + static_cast<float>(k % 7);
        }
        batches.write(b);
        if (rev % 25 == 0) {
          smc_data_SupervisorSituation st{};
          smc::wire::set_string(st.machine_id, id);
          st.machine_time_ns = s.machine_time_ns;
          st.sequence_number = rev;
          st.active_steps = (rev / 25) % 2 ? 0x8 : 0x2;
          st.modules_active = 0x39b;
          situations.write(st);
        }
        ++published;
      }
    }
  });

  const pid_t pid = dash.pid();
  std::this_thread::sleep_for(3s);  // warm-up: discovery, first samples
  const double idle_probe = cpu_seconds(pid);
  (void)idle_probe;
  for (auto& s : client_samples) s->recording = true;
  dds_only.recording = true;
  const double cpu0 = cpu_seconds(pid);
  const auto t0 = Clock::now();
  const uint64_t pub0 = published.load();
  std::this_thread::sleep_for(std::chrono::seconds(seconds));
  const double cpu1 = cpu_seconds(pid);
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  const uint64_t pub1 = published.load();
  for (auto& s : client_samples) s->recording = false;
  dds_only.recording = false;
  const auto stats_body = smc::test::http(port, "GET", "/api/stats").body;
  stop = true;
  for (auto& t : threads) t.join();

  std::vector<double> cell_all;
  std::vector<double> mill_all;
  for (size_t c = 0; c < client_samples.size(); ++c) {
    auto& v = static_cast<int>(c) < cell_clients ? cell_all : mill_all;
    v.insert(v.end(), client_samples[c]->ms.begin(), client_samples[c]->ms.end());
  }
  const double expected_per_cell_client = static_cast<double>(pub1 - pub0);
  std::printf(
      "smc-bench-dashboard, %s: %d mills x 25 rev/s (summary + 80-sample batch each), %d s, "
      "%d cell-view + %d mill-view stream clients\n",
      dds.name(), mills, seconds, cell_clients, mill_clients);
  std::printf("%-44s %8s %8s %8s %8s\n", "force summary: write -> arrival", "n", "p50 ms", "p99 ms",
              "max ms");
  auto row = [](const char* name, const std::vector<double>& v) {
    std::printf("%-44s %8zu %8.3f %8.3f %8.3f\n", name, v.size(), percentile(v, 0.5),
                percentile(v, 0.99), v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
  };
  row("baseline: DDS one hop (echo round trip / 2)", dds_only.ms);
  row("dashboard stream, cell-view clients", cell_all);
  row("dashboard stream, mill-view clients (+raw)", mill_all);
  if (!dds_only.ms.empty() && !cell_all.empty()) {
    std::printf("ratio p50 stream/DDS: %.1fx   p99: %.1fx\n",
                percentile(cell_all, 0.5) / percentile(dds_only.ms, 0.5),
                percentile(cell_all, 0.99) / percentile(dds_only.ms, 0.99));
  }
  std::printf("summaries delivered per cell-view client: %.1f %% of written\n",
              cell_clients > 0 ? 100.0 * static_cast<double>(cell_all.size()) /
                                     (expected_per_cell_client * cell_clients)
                               : 0.0);
  std::printf("dashboard CPU: %.1f %% of one core (%.2f s over %.1f s)\n",
              100.0 * (cpu1 - cpu0) / wall, cpu1 - cpu0, wall);
  std::printf("dashboard /api/stats: %s\n", stats_body.substr(0, 400).c_str());
  return cell_all;
}

int main(int argc, char** argv) {
  int mills = 10;
  int seconds = 10;
  int cell_clients = 2;
  int mill_clients = 2;
  CLI::App app{
      "smc-bench-dashboard: latency from a force summary's write on DDS to its arrival at the "
      "dashboard's\n"
      "push-stream clients, beside DDS alone, and the dashboard's CPU; over plain DDS and "
      "under DDS Security."};
  app.add_option("--mills", mills, "mills streaming at 1500 rpm")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  app.add_option("--seconds", seconds, "seconds measured")
      ->check(CLI::Range(2, 600))
      ->capture_default_str();
  app.add_option("--cell-clients", cell_clients, "push-stream clients on the cell's stream")
      ->check(CLI::Range(0, 50))
      ->capture_default_str();
  app.add_option("--mill-clients", mill_clients, "push-stream clients on each mill's stream")
      ->check(CLI::Range(0, 50))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (std::getenv("CYCLONEDDS_URI") == nullptr) {
    ::setenv("CYCLONEDDS_URI", "file://" SMC_DDS_PROFILE_PATH, 1);
  }
  const smc::test::SecureDds plain;
  const smc::test::SecureDds secure(7, {});
  const auto p = measure(plain, mills, seconds, cell_clients, mill_clients);
  const auto q = measure(secure, mills, seconds, cell_clients, mill_clients);
  std::printf(
      "DDS Security beside plain DDS, cell-view stream: p50 %+.3f ms, p99 %+.3f ms "
      "(%.3f -> %.3f, %.3f -> %.3f)\n",
      percentile(q, 0.5) - percentile(p, 0.5), percentile(q, 0.99) - percentile(p, 0.99),
      percentile(p, 0.5), percentile(q, 0.5), percentile(p, 0.99), percentile(q, 0.99));
  return 0;
}
