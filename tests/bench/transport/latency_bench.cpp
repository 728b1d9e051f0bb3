// Round-trip latency of a ForceSummary sample through smc_transport between
// two processes on loopback, beside ddsperf ping/pong with the same payload
// size, measured in the same run. Prints p50/p99 of both and their ratio.
// Then the round trip of an OperatorCommand (reliable; signed under DDS
// Security) over plain DDS and under DDS Security (a PKI of its own,
// deploy/security/pki.sh; both processes on the cell's identity), and what
// security adds (issue 16's goal: < 1 ms at p99).
//
//   build/release/bin/smc-bench-transport-latency [--samples N] [--ddsperf-s S]
//
// ddsperf prints half the round-trip time; this program doubles it so that
// both columns are full round trips.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "secure_dds.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"

using namespace smc::transport;
using Clock = std::chrono::steady_clock;

namespace {

struct Percentiles {
  double p50_us = 0, p99_us = 0;
  size_t n = 0;
};

Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, size_t(q * double(v.size())))]; };
  p.p50_us = at(0.50);
  p.p99_us = at(0.99);
  p.n = v.size();
  return p;
}

// The id a round trip is matched by: a force summary's revolution, an
// operator command's command id.
void set_id(smc_data_ForceSummary& s, uint64_t i) { s.revolution = static_cast<uint32_t>(i); }
uint64_t get_id(const smc_data_ForceSummary& s) { return s.revolution; }
void set_id(smc_data_OperatorCommand& c, uint64_t i) { c.command_id = i; }
uint64_t get_id(const smc_data_OperatorCommand& c) { return c.command_id; }

// Round trips of T through the echo process, over `dds` (plain or secure).
template <class T>
Percentiles measure_wrapper(size_t samples, const smc::test::SecureDds& dds) {
  const std::string partition = smc::test::unique_partition("bench");
  smc::test::ChildProcess echo(
      dds.child({smc::test::bin_path("smc-transport-echo"), "--partition", partition, "--domain",
                 std::to_string(dds.domain()), "--idle-s", "30"},
                "cell"));
  if (!echo.wait_for_line("ready")) {
    std::fprintf(stderr, "echo process did not start\n");
    std::exit(2);
  }
  Participant req(dds.participant(partition + ".req"));
  Participant rep(dds.participant(partition + ".rep"));
  Topic<T> out_topic(req), in_topic(rep);
  // The force-summary topic is best-effort (telemetry); on loopback nothing
  // is lost in practice, and a loss would show as a timeout below.
  const QosProfile qos = out_topic.qos();
  Writer<T> w(out_topic, qos);
  Reader<T> r(in_topic, qos);
  if (!w.wait_for_readers(1, std::chrono::seconds(10)) ||
      !r.wait_for_writers(1, std::chrono::seconds(10))) {
    std::fprintf(stderr, "echo did not match\n");
    std::exit(2);
  }
  WaitSet ws(rep);
  ws.attach(r, 1);
  std::vector<int64_t> fired;
  fired.reserve(8);
  T s{};
  smc::wire::set_string(s.machine_id, "mill-01");
  std::vector<double> rtt;
  rtt.reserve(samples);
  const size_t warmup = std::max<size_t>(200, samples / 20);
  for (size_t i = 0; i < samples + warmup; ++i) {
    set_id(s, i + 1);
    const auto t0 = Clock::now();
    w.write(s);
    bool got = false;
    while (!got) {
      ws.wait(std::chrono::seconds(2), fired);
      if (fired.empty()) {
        std::fprintf(stderr, "timeout waiting for echo of %zu\n", i);
        std::exit(2);
      }
      r.take([&](const T& back, const SampleInfo& info) {
        if (info.valid_data && get_id(back) == i + 1) got = true;
      });
    }
    const auto t1 = Clock::now();
    if (i >= warmup) rtt.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  return percentiles(std::move(rtt));
}

// Runs ddsperf ping/pong for `seconds`; returns the medians over its
// per-second reports of p50 and p99, doubled to full round trips.
std::optional<Percentiles> measure_ddsperf(int seconds, int payload) {
  const std::string secs = std::to_string(seconds);
  smc::test::ChildProcess pong(
      {"/usr/bin/ddsperf", "-D", std::to_string(seconds + 2), "pong", "waitset"});
  std::string out;
  {
    const std::string cmd =
        "/usr/bin/ddsperf -D " + secs + " ping size " + std::to_string(payload) + " waitset 2>&1";
    FILE* f = ::popen(cmd.c_str(), "r");
    if (f == nullptr) return std::nullopt;
    char buf[512];
    while (std::fgets(buf, sizeof buf, f) != nullptr) out += buf;
    ::pclose(f);
  }
  std::vector<double> p50s, p99s;
  size_t pos = 0;
  while ((pos = out.find(" 50% ", pos)) != std::string::npos) {
    const double p50 = std::atof(out.c_str() + pos + 5);
    const size_t q = out.find(" 99% ", pos);
    if (q == std::string::npos) break;
    const double p99 = std::atof(out.c_str() + q + 5);
    p50s.push_back(2 * p50);
    p99s.push_back(2 * p99);
    pos = q;
  }
  if (p50s.size() < 2) {
    std::fprintf(stderr, "ddsperf gave no latency lines:\n%s\n", out.c_str());
    return std::nullopt;
  }
  // Drop the first report (discovery, warm-up), then take medians.
  p50s.erase(p50s.begin());
  p99s.erase(p99s.begin());
  std::sort(p50s.begin(), p50s.end());
  std::sort(p99s.begin(), p99s.end());
  Percentiles p;
  p.p50_us = p50s[p50s.size() / 2];
  p.p99_us = p99s[p99s.size() / 2];
  p.n = p50s.size();
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  size_t samples = 20000;
  int ddsperf_s = 6;
  CLI::App app{
      "smc-bench-transport-latency: ForceSummary round trip through smc_transport between "
      "two processes\n"
      "on loopback beside ddsperf ping/pong, then an OperatorCommand's round trip over plain "
      "DDS and\n"
      "under DDS Security (same run)."};
  app.add_option("--samples", samples, "round trips measured")
      ->check(CLI::Range(size_t{1}, size_t{100000000}))
      ->capture_default_str();
  app.add_option("--ddsperf-s", ddsperf_s, "seconds of ddsperf ping/pong")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (std::getenv("CYCLONEDDS_URI") == nullptr) {
    // ddsperf must use the loopback profile too.
    ::setenv("CYCLONEDDS_URI", (std::string("file://") + SMC_DDS_PROFILE_PATH).c_str(), 1);
  }
  // Serialized ForceSummary: 4 (CDR header) + 4+8 ("mill-01") + 4 pad + 8 + 4 + 2+2 + 8*4 + 2.
  const int payload = 72;
  std::printf("ForceSummary round trip, two processes on loopback (%zu samples)\n", samples);
  const smc::test::SecureDds plain;
  const Percentiles ours = measure_wrapper<smc_data_ForceSummary>(samples, plain);
  std::printf("  smc_transport      p50 %8.1f us   p99 %8.1f us\n", ours.p50_us, ours.p99_us);
  const auto ref = measure_ddsperf(ddsperf_s, payload);
  if (!ref) return 2;
  std::printf("  ddsperf (size %d)  p50 %8.1f us   p99 %8.1f us   (%zu one-second reports)\n",
              payload, ref->p50_us, ref->p99_us, ref->n);
  const double r50 = ours.p50_us / ref->p50_us, r99 = ours.p99_us / ref->p99_us;
  std::printf("  ratio              p50 %8.2f      p99 %8.2f      (goal: p50 <= 1.5) %s\n", r50,
              r99, r50 <= 1.5 ? "MET" : "MISSED");

  const smc::test::SecureDds secure(7, {});
  std::printf("OperatorCommand round trip, two processes on loopback (%zu samples)\n", samples);
  const Percentiles cmd_plain = measure_wrapper<smc_data_OperatorCommand>(samples, plain);
  std::printf("  plain DDS          p50 %8.1f us   p99 %8.1f us\n", cmd_plain.p50_us,
              cmd_plain.p99_us);
  const Percentiles cmd_secure = measure_wrapper<smc_data_OperatorCommand>(samples, secure);
  std::printf("  DDS Security       p50 %8.1f us   p99 %8.1f us\n", cmd_secure.p50_us,
              cmd_secure.p99_us);
  const double added = cmd_secure.p99_us - cmd_plain.p99_us;
  std::printf("  added by security  p50 %+8.1f us   p99 %+8.1f us   (goal: p99 < +1000 us) %s\n",
              cmd_secure.p50_us - cmd_plain.p50_us, added, added < 1000 ? "MET" : "MISSED");
  return 0;
}
