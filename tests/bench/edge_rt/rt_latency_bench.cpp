// Wake-up latency of the edge's real-time loop (smc_edge_rt RtLoop on the
// wall clock) beside cyclictest (Debian package rt-tests) at the same period,
// duration, priority, CPU and memory locking, measured one after the other
// in the same run, optionally with a busy thread on another CPU during both.
//
//   build/<dir>/bin/smc-bench-rt-latency [--seconds 10] [--load] [--period-us 500]
//                                        [--priority 80] [--cpu N] [--no-cyclictest]
//
// Prints p50 / p99 / max wake-up latency, the wake-ups later than one
// period, the loop's overruns, and RtLoop / cyclictest ratios. Both
// histograms are summarised by the same code (1 µs buckets below 1 ms,
// latency truncated to whole µs as cyclictest does). Like cyclictest, the
// bench holds /dev/cpu_dma_latency at 0 during the RtLoop run, when it can.
//
// Exit status: 0 when both measurements ran, CLI11's on a usage error, 2 when
// cyclictest is missing or its output cannot be read.

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <thread>

#include "smc/common/clock.hpp"
#include "smc/edge/rt/latency_histogram.hpp"
#include "smc/edge/rt/rt_loop.hpp"
#include "smc/edge/rt/rt_setup.hpp"

namespace {

using smc::Nanos;
using smc::edge::rt::LatencySnapshot;

struct Args {
  int seconds = 10;
  bool load = false;
  int period_us = 500;
  int priority = 80;
  int cpu = -2;  // -2: pick the last allowed CPU; -1: no pinning
  bool cyclictest = true;
};

// CPUs this process may run on, lowest first.
std::string allowed_cpus(int& first, int& last, int& count) {
  cpu_set_t set;
  CPU_ZERO(&set);
  first = -1;
  last = -1;
  count = 0;
  std::string s;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return s;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(static_cast<std::size_t>(c), &set)) {
      if (first < 0) first = c;
      last = c;
      ++count;
      if (!s.empty()) s += ',';
      s += std::to_string(c);
    }
  }
  return s;
}

// A plain busy loop pinned to one CPU, SCHED_OTHER.
class CpuHog {
 public:
  explicit CpuHog(int cpu) {
    thread_ = std::thread([this, cpu] {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<std::size_t>(cpu), &set);
      pinned_ = pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
      started_.store(true, std::memory_order_release);
      std::uint64_t x = 0;
      while (!stop_.load(std::memory_order_relaxed)) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
      }
      sink_.store(x, std::memory_order_relaxed);
    });
    while (!started_.load(std::memory_order_acquire)) std::this_thread::yield();
  }
  ~CpuHog() {
    stop_.store(true, std::memory_order_relaxed);
    thread_.join();
  }
  bool pinned() const { return pinned_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<bool> started_{false};
  std::atomic<std::uint64_t> sink_{0};
  bool pinned_ = false;
  std::thread thread_;
};

// Holds /dev/cpu_dma_latency at 0 µs while alive (what cyclictest does by
// default), so that both measurements see the same C-state policy.
class DmaLatencyZero {
 public:
  DmaLatencyZero() {
    fd_ = ::open("/dev/cpu_dma_latency", O_RDWR | O_CLOEXEC);
    if (fd_ < 0) return;
    const std::int32_t zero = 0;
    if (::write(fd_, &zero, sizeof zero) != static_cast<ssize_t>(sizeof zero)) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~DmaLatencyZero() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

struct Result {
  LatencySnapshot lat;
  std::uint64_t overruns = 0;
  bool has_overruns = false;
  std::uint64_t late_by_period = 0;  // wake-ups later than one period
};

std::uint64_t count_at_or_above(const LatencySnapshot& s, Nanos limit) {
  std::uint64_t n = 0;
  for (std::size_t b = LatencySnapshot::bucket_of(limit); b < LatencySnapshot::kBuckets; ++b) {
    n += s.bucket_count(b);
  }
  return n;
}

// The tick does next to nothing, as cyclictest's thread does.
struct TickCtx {
  std::uint64_t ticks = 0;
  std::uint64_t overrun_ticks = 0;
};

void bench_tick(void* ctx, const smc::edge::rt::TickInfo& info) noexcept {
  auto* c = static_cast<TickCtx*>(ctx);
  ++c->ticks;
  if (info.overrun) ++c->overrun_ticks;
}

Result run_rt_loop(const Args& a, int cpu, smc::edge::rt::RtSetupReport& report, bool& dma_held) {
  smc::RealClock clock;
  smc::edge::rt::RtOptions opts;
  opts.period = Nanos{std::int64_t{a.period_us} * 1000};
  opts.priority = a.priority;
  opts.cpu = cpu;
  opts.lock_memory = true;
  DmaLatencyZero dma;
  dma_held = dma.held();
  smc::edge::rt::RtLoop loop(opts, clock);
  TickCtx ctx;
  loop.start(bench_tick, &ctx);
  report = loop.setup_report();
  std::this_thread::sleep_for(std::chrono::seconds(a.seconds));
  loop.stop();
  Result r;
  r.lat = loop.latency();
  r.overruns = loop.overruns();
  r.has_overruns = true;
  r.late_by_period = count_at_or_above(r.lat, opts.period + Nanos{1000});
  return r;
}

bool find_in_path(const char* name, std::string& out) {
  const char* path = std::getenv("PATH");
  std::string p = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  p += ":/usr/sbin:/sbin";
  std::size_t start = 0;
  while (start <= p.size()) {
    const std::size_t end = p.find(':', start);
    const std::string dir =
        p.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!dir.empty()) {
      const std::string candidate = dir + "/" + name;
      if (::access(candidate.c_str(), X_OK) == 0) {
        out = candidate;
        return true;
      }
    }
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return false;
}

// Runs cyclictest and loads its histogram. cyclictest's overflow samples
// (above the histogram range) are added at its reported maximum.
bool run_cyclictest(const std::string& exe, const Args& a, int cpu, int priority,
                    std::string& command, Result& r, std::string& error) {
  constexpr int kHistUs = 100'000;  // same range as LatencySnapshot
  command = exe + " -m -q -t1 -i" + std::to_string(a.period_us) + " -p" + std::to_string(priority) +
            " -D" + std::to_string(a.seconds) + " -h" + std::to_string(kHistUs);
  if (cpu >= 0) command += " -a" + std::to_string(cpu);
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) {
    error = "cannot run " + command;
    return false;
  }
  char line[512];
  std::uint64_t overflows = 0;
  long max_us = -1;
  std::uint64_t total = 0;
  bool have_total = false;
  std::string other;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    unsigned long bin = 0;
    unsigned long long n = 0;
    char tail = '\0';
    if (std::sscanf(line, "%lu %llu%c", &bin, &n, &tail) >= 2 && line[0] != '#') {
      if (n > 0) r.lat.add(Nanos{static_cast<std::int64_t>(bin) * 1000}, n);
    } else if (std::sscanf(line, "# Max Latencies: %ld", &max_us) == 1) {
    } else if (std::sscanf(line, "# Histogram Overflows: %llu", &n) == 1) {
      overflows = n;
    } else if (std::sscanf(line, "# Total: %llu", &n) == 1) {
      total = n;
      have_total = true;
    } else if (other.size() < 2000 && line[0] != '#') {
      other += line;
    }
  }
  const int status = ::pclose(pipe);
  if (max_us >= 0 && overflows > 0) {
    r.lat.add(Nanos{static_cast<std::int64_t>(max_us) * 1000}, overflows);
  }
  if (status != 0 || !have_total || r.lat.count() == 0) {
    error = "cyclictest failed (status " + std::to_string(status) + "): " + other;
    return false;
  }
  if (total + overflows != r.lat.count()) {
    error = "cyclictest histogram total " + std::to_string(total) + " + overflows " +
            std::to_string(overflows) + " != parsed " + std::to_string(r.lat.count());
    return false;
  }
  r.late_by_period = count_at_or_above(r.lat, Nanos{std::int64_t{a.period_us} * 1000 + 1000});
  return true;
}

double us(Nanos t) { return static_cast<double>(t.count()) / 1000.0; }

void print_row(const char* name, const Result& r) {
  char overruns[32] = "-";
  if (r.has_overruns) {
    std::snprintf(overruns, sizeof overruns, "%llu", static_cast<unsigned long long>(r.overruns));
  }
  std::printf("%-12s %9llu %8.0f %8.0f %8.0f %8.1f %10llu %9s\n", name,
              static_cast<unsigned long long>(r.lat.count()), us(r.lat.percentile(0.50)),
              us(r.lat.percentile(0.99)), us(r.lat.max()), us(r.lat.mean()),
              static_cast<unsigned long long>(r.late_by_period), overruns);
}

void print_ratio(Nanos ours, Nanos theirs, const char* what) {
  if (theirs.count() <= 0) {
    std::printf("  %s: -", what);
  } else {
    std::printf("  %s: %.2f", what,
                static_cast<double>(ours.count()) / static_cast<double>(theirs.count()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  CLI::App app{
      "smc-bench-rt-latency: wake-up latency of the edge's real-time loop on the wall clock "
      "beside\n"
      "cyclictest at the same period, duration, priority, CPU and memory locking (same run)."};
  app.add_option("--seconds", a.seconds, "seconds each measurement runs")
      ->check(CLI::Range(1, 86400))
      ->capture_default_str();
  app.add_flag("--load", a.load, "a busy thread on another CPU during both");
  app.add_option("--period-us", a.period_us, "the loop's period, us")
      ->check(CLI::Range(50, 1000000))
      ->capture_default_str();
  app.add_option("--priority", a.priority, "SCHED_FIFO priority")
      ->check(CLI::Range(1, 99))
      ->capture_default_str();
  app.add_option("--cpu", a.cpu, "CPU to pin to, -1: none (default: the last allowed)")
      ->check(CLI::Range(-1, 4095));
  bool no_cyclictest = false;
  app.add_flag("--no-cyclictest", no_cyclictest, "the loop alone");
  CLI11_PARSE(app, argc, argv);
  a.cyclictest = !no_cyclictest;

  int first = -1;
  int last = -1;
  int ncpu = 0;
  const std::string cpus = allowed_cpus(first, last, ncpu);
  const int rt_cpu = a.cpu == -2 ? last : a.cpu;
  int hog_cpu = -1;
  if (a.load) {
    hog_cpu = rt_cpu == first ? last : first;
    if (hog_cpu == rt_cpu) hog_cpu = -1;
  }

  std::string cyclictest;
  if (a.cyclictest && !find_in_path("cyclictest", cyclictest)) {
    std::fprintf(stderr,
                 "cyclictest not found: install the Debian package rt-tests "
                 "(apt-get install -y rt-tests), or pass --no-cyclictest\n");
    return 2;
  }

  std::printf("smc-bench-rt-latency: period %d us, %d s per measurement, allowed CPUs %s\n",
              a.period_us, a.seconds, cpus.c_str());
  std::optional<CpuHog> hog;
  if (a.load) {
    if (hog_cpu < 0) {
      std::printf("load: no other CPU to load; running unloaded\n");
    } else {
      hog.emplace(hog_cpu);
      std::printf("load: busy thread on cpu %d (%s) during both measurements\n", hog_cpu,
                  hog->pinned() ? "pinned" : "NOT pinned");
    }
  } else {
    std::printf("load: none\n");
  }

  std::fprintf(stderr, "measuring RtLoop for %d s ...\n", a.seconds);
  smc::edge::rt::RtSetupReport report;
  bool dma_held = false;
  const Result ours = run_rt_loop(a, rt_cpu, report, dma_held);
  smc::edge::rt::RtOptions shown;
  shown.priority = a.priority;
  shown.cpu = rt_cpu;
  std::printf("RtLoop set-up: %s; /dev/cpu_dma_latency held at 0: %s\n",
              smc::edge::rt::summary(report, shown).c_str(), dma_held ? "yes" : "no");
  for (std::size_t pos = 0; pos < report.notes.size();) {
    const std::size_t nl = report.notes.find('\n', pos);
    std::printf("  %s\n", report.notes.substr(pos, nl - pos).c_str());
    if (nl == std::string::npos) break;
    pos = nl + 1;
  }

  Result theirs;
  std::string command;
  bool have_theirs = false;
  if (a.cyclictest) {
    // Same policy as the loop actually got: FIFO at its priority, or
    // SCHED_OTHER (-p0) when FIFO was refused.
    const int prio = report.sched_fifo ? report.priority : 0;
    std::fprintf(stderr, "measuring cyclictest for %d s ...\n", a.seconds);
    std::string error;
    have_theirs = run_cyclictest(cyclictest, a, rt_cpu, prio, command, theirs, error);
    std::printf("cyclictest: %s\n", command.c_str());
    if (!have_theirs) std::printf("cyclictest: %s\n", error.c_str());
  }

  std::printf("\n%-12s %9s %8s %8s %8s %8s %10s %9s\n", "", "samples", "p50 us", "p99 us", "max us",
              "mean us", "late>per.", "overruns");
  print_row("RtLoop", ours);
  if (have_theirs) {
    print_row("cyclictest", theirs);
    std::printf("RtLoop / cyclictest:");
    print_ratio(ours.lat.percentile(0.50), theirs.lat.percentile(0.50), "p50");
    print_ratio(ours.lat.percentile(0.99), theirs.lat.percentile(0.99), "p99");
    print_ratio(ours.lat.max(), theirs.lat.max(), "max");
    std::printf("\n");
  }
  return a.cyclictest && !have_theirs ? 2 : 0;
}
