// smc-edge hal-samples: is the edge getting every servo period of a LinuxCNC
// machine? Reads the sampler stream the LinuxCNC drive reads and reports
// continuity, for machine builders and the tests.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

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
      "largest backlog, the path travelled, the spindle's turns and whether the force sensor\n"
      "gives the wideband F_y channel (module E's vibration estimate), as JSON. Exit 0 when no\n"
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
        "\"spindle_revs\": %.3f, \"last_velocity_mm_s\": %.4f, \"wideband_fy\": %s, "
        "\"wideband_samples\": %d, \"complete\": %s}\n",
        static_cast<unsigned long long>(s->records()), static_cast<unsigned long long>(s->lost()),
        static_cast<unsigned long long>(s->repeated()), s->overruns(), backlog_max, wall,
        s->records() > 0 ? x_min : 0.0, s->records() > 0 ? x_max : 0.0,
        s->records() > 0 ? r.spindle_revs - first.spindle_revs : 0.0,
        s->records() > 0 ? r.velocity_mm_s : 0.0, r.fy_wide_present ? "true" : "false",
        r.fy_wide_present ? std::max(1, static_cast<int>(r.fy_wide_samples)) : 0,
        complete ? "true" : "false");
    if (!complete) throw Failure(1, "timed out after " + std::to_string(args->timeout_s) + " s");
    if (s->lost() > 0 || s->repeated() > 0) {
      throw Failure(1, "records lost or repeated: the edge would not see every servo period");
    }
  });
}

namespace {

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Reads what is waiting; the last record read.
void drain(linuxcnc::HalSampleStream& s, linuxcnc::HalRecord& last) {
  s.heartbeat(now_ns());
  while (s.read(last)) {
  }
}

// Reads until `pred(record)` or the deadline; false on the deadline.
template <class P>
bool read_until(linuxcnc::HalSampleStream& s, linuxcnc::HalRecord& r, P pred,
                std::chrono::steady_clock::time_point deadline) {
  while (std::chrono::steady_clock::now() < deadline) {
    s.heartbeat(now_ns());  // this tool is the edge while it runs
    if (!s.read(r)) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
      continue;
    }
    if (pred(r)) return true;
  }
  return false;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

}  // namespace

void add_hal_latency(CLI::App& app) {
  struct Args {
    std::string component = "smc-edge-probe";
    int steps = 20;
    double low = 0.25, high = 0.5, period_ms = 0.5, timeout_s = 60;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "hal-feed-latency",
      "While LinuxCNC runs a feed move with M52 P1, step the edge's adaptive-feed pin between\n"
      "two shares of F and measure, in servo periods from LinuxCNC's own sampled path velocity,\n"
      "how long each command takes to change the velocity and to settle at the new feed; then\n"
      "hold the feed with the feed-inhibit pin (time to standstill) and release it. Prints JSON\n"
      "(p50, p99, max in ms). Run it as LinuxCNC's user while a program runs.");
  sub->add_option("--component", args->component, "HAL component name to join as")
      ->capture_default_str();
  sub->add_option("--steps", args->steps, "Commands to send")->check(CLI::Range(2, 10000));
  sub->add_option("--low", args->low, "Lower share of F")->check(CLI::Range(0.01, 1.0));
  sub->add_option("--high", args->high, "Higher share of F")->check(CLI::Range(0.01, 1.0));
  sub->add_option("--period-ms", args->period_ms, "Servo period (the INI's SERVO_PERIOD)")
      ->capture_default_str();
  sub->add_option("--timeout", args->timeout_s, "Give up after this many seconds")
      ->capture_default_str();
  sub->callback([args] {
    std::unique_ptr<linuxcnc::HalSampleStream> s;
    try {
      s = std::make_unique<linuxcnc::HalSampleStream>(args->component, 0, true);
    } catch (const std::runtime_error& e) {
      throw Failure(2, e.what());
    }
    if (!s->outputs_linked()) {
      throw Failure(2,
                    "no smc-adaptive-feed / smc-feed-inhibit signals in HAL: load "
                    "deploy/linuxcnc/smc-edge.hal");
    }
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                               std::chrono::duration<double>(args->timeout_s));
    linuxcnc::HalRecord r;
    double share = args->high;
    s->set_adaptive_feed(share);
    // A feed move at a steady speed first.
    int steady = 0;
    double last_v = -1;
    if (!read_until(
            *s, r,
            [&](const linuxcnc::HalRecord& x) {
              steady = (x.velocity_mm_s > 0.5 && std::fabs(x.velocity_mm_s - last_v) < 1e-6)
                           ? steady + 1
                           : 0;
              last_v = x.velocity_mm_s;
              return steady >= 100;
            },
            deadline)) {
      throw Failure(1, "no steady feed move seen: run a program with M52 P1 while measuring");
    }
    std::vector<double> start_ms, settle_ms;
    int settled_steps = 0;
    for (int i = 0; i < args->steps; ++i) {
      drain(*s, r);
      const double v0 = r.velocity_mm_s;
      const double next = share == args->high ? args->low : args->high;
      const double v1 = v0 * next / share;  // the same F, the new share
      const std::uint32_t at = r.sample_no;
      s->set_adaptive_feed(next);
      share = next;
      const double step = v1 - v0;
      if (!read_until(
              *s, r,
              [&](const linuxcnc::HalRecord& x) {
                return std::fabs(x.velocity_mm_s - v0) > 0.01 * std::fabs(step);
              },
              deadline)) {
        break;
      }
      start_ms.push_back((r.sample_no - at) * args->period_ms);
      if (!read_until(
              *s, r,
              [&](const linuxcnc::HalRecord& x) {
                return std::fabs(x.velocity_mm_s - v1) < 0.01 * std::fabs(v1);
              },
              deadline)) {
        break;
      }
      settle_ms.push_back((r.sample_no - at) * args->period_ms);
      ++settled_steps;
      // Steady at the new feed for 20 periods before the next command.
      int still = 0;
      (void)read_until(
          *s, r,
          [&](const linuxcnc::HalRecord& x) {
            still = std::fabs(x.velocity_mm_s - v1) < 0.01 * std::fabs(v1) ? still + 1 : 0;
            return still >= 20;
          },
          deadline);
    }
    // Then the hold: feed-inhibit stops the axis (LinuxCNC decelerates at
    // its limit), and releasing it lets the cut go on.
    double stop_ms = NAN, resume_ms = NAN;
    if (settled_steps == args->steps) {
      drain(*s, r);
      const std::uint32_t at = r.sample_no;
      s->set_feed_inhibit(true);
      if (read_until(
              *s, r, [](const linuxcnc::HalRecord& x) { return x.velocity_mm_s < 1e-6; },
              deadline)) {
        stop_ms = (r.sample_no - at) * args->period_ms;
      }
      const std::uint32_t released = r.sample_no;
      s->set_feed_inhibit(false);
      if (read_until(
              *s, r, [](const linuxcnc::HalRecord& x) { return x.velocity_mm_s > 0.5; },
              deadline)) {
        resume_ms = (r.sample_no - released) * args->period_ms;
      }
    }
    s->set_feed_inhibit(false);
    s->set_adaptive_feed(1.0);
    std::printf(
        "{\"steps\": %d, \"settled\": %d, \"change_p50_ms\": %.2f, \"change_p99_ms\": %.2f, "
        "\"change_max_ms\": %.2f, \"settle_p50_ms\": %.2f, \"settle_p99_ms\": %.2f, "
        "\"settle_max_ms\": %.2f, \"inhibit_stop_ms\": %.2f, \"resume_ms\": %.2f, "
        "\"lost\": %llu}\n",
        args->steps, settled_steps, percentile(start_ms, 0.5), percentile(start_ms, 0.99),
        percentile(start_ms, 1.0), percentile(settle_ms, 0.5), percentile(settle_ms, 0.99),
        percentile(settle_ms, 1.0), stop_ms, resume_ms, static_cast<unsigned long long>(s->lost()));
    if (std::isnan(stop_ms) || std::isnan(resume_ms)) {
      throw Failure(1, "the feed-inhibit pin did not stop and release the axis");
    }
    if (settled_steps < args->steps) {
      throw Failure(1, "only " + std::to_string(settled_steps) + " of " +
                           std::to_string(args->steps) +
                           " commands were followed (did the program end?)");
    }
  });
}

}  // namespace smc::edge::cli
