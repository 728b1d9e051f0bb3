#pragma once
// The wall-clock real-time loop: one thread calls a tick function at a fixed
// period (2 kHz by default), sleeping to absolute deadlines
// (Clock::sleep_until, i.e. clock_nanosleep TIMER_ABSTIME on a RealClock).
//
// Schedule. Tick k is due at t0 + k' * period, where t0 is one period after
// start and k' counts period boundaries (k' = k until a boundary is missed).
// A tick that finishes after the next boundary makes the loop skip to the
// first boundary still ahead of it: no burst of catch-up ticks. The skipped
// boundaries are counted (missed_periods()).
//
// Overrun. TickInfo::overrun is true on a tick when
//   - this tick woke more than RtOptions::overrun_threshold late (one
//     period by default), or
//   - the previous tick ran past its deadline (the boundary after it), so
//     boundaries were skipped before this one -- unless the previous tick
//     was itself flagged for waking up past that deadline: one stall gives
//     one flagged tick, or
//   - force_overrun() was called since the previous tick (test hook).
// overruns() counts the ticks delivered with overrun set. The loop only
// reports; the tick function (the edge core) decides what an overrun means
// (a feed hold).
//
// Threads. start() runs the loop on a new thread, after
// prepare_realtime_thread() on it (SCHED_FIFO, mlockall, affinity, stack;
// see setup_report()). run_for_ticks() runs the same loop on the calling
// thread without any set-up: with a VirtualClock it is deterministic and as
// fast as the CPU allows.
//
// Real-time safe (no allocation, no lock, no system call but the clock):
//   the loop itself, between the first and the last tick (asserted by
//   tests/unit/edge_rt with a counting operator new);
//   force_overrun(), request_stop(), ticks(), overruns(), missed_periods(),
//   max_tick_duration(), running(), latency() (no allocation; copies ~22 KB).
// Not real-time: constructor, destructor, start(), stop(), run_for_ticks(),
//   setup_report().

#include <atomic>
#include <cstdint>
#include <thread>

#include "smc/common/clock.hpp"
#include "smc/edge/rt/latency_histogram.hpp"
#include "smc/edge/rt/rt_setup.hpp"

namespace smc::edge::rt {

struct TickInfo {
  std::uint64_t index = 0;  // 0, 1, 2, ... one per delivered tick, no gaps
  Nanos scheduled{0};       // the period boundary this tick belongs to
  Nanos woke{0};            // clock time when the loop woke for it
  Nanos lateness{0};        // woke - scheduled (>= 0 on a sane clock)
  bool overrun = false;     // see "Overrun" above
};

// Runs on the loop thread, once per period. Must be real-time safe.
using TickFn = void (*)(void* ctx, const TickInfo& info) noexcept;

class RtLoop {
 public:
  // Not real-time. `clock` must outlive the loop. Throws
  // std::invalid_argument when the period is not positive.
  RtLoop(const RtOptions& options, Clock& clock);
  // Stops and joins the thread if it runs.
  ~RtLoop();
  RtLoop(const RtLoop&) = delete;
  RtLoop& operator=(const RtLoop&) = delete;

  // Not real-time. Starts the loop thread; returns once the thread has done
  // its set-up (setup_report() is then valid) and is about to sleep until
  // its first deadline, one period from now. Throws std::logic_error when
  // already running, std::system_error when no thread can be made.
  void start(TickFn fn, void* ctx);
  // Not real-time. Asks the loop to stop and joins it: returns within about
  // one period plus the running tick. Idempotent.
  void stop();
  // Any thread, real-time safe: the loop ends after the current tick (from
  // inside a tick, or from another thread; stop() still has to join).
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }
  bool running() const noexcept { return running_.load(std::memory_order_acquire); }

  // Not real-time. Runs `n` ticks on the calling thread (fewer if
  // request_stop() is called from a tick), no thread and no real-time set-up.
  // The first call schedules its first tick one period after the clock's
  // now(); later calls continue the same schedule. Throws std::logic_error
  // while the thread runs.
  void run_for_ticks(std::uint64_t n, TickFn fn, void* ctx);

  // Any thread, real-time safe. Test hook: the next tick carries
  // overrun = true and is counted in overruns(), as if it had been late.
  void force_overrun() noexcept { force_overrun_.store(true, std::memory_order_release); }

  // Any thread, real-time safe. Totals since construction.
  std::uint64_t ticks() const noexcept { return ticks_.load(std::memory_order_acquire); }
  std::uint64_t overruns() const noexcept { return overruns_.load(std::memory_order_acquire); }
  std::uint64_t missed_periods() const noexcept { return missed_.load(std::memory_order_acquire); }
  // Longest time from wake-up to the end of a tick (tick function included).
  Nanos max_tick_duration() const noexcept {
    return Nanos{max_tick_ns_.load(std::memory_order_relaxed)};
  }
  // Wake-up lateness of every tick so far.
  LatencySnapshot latency() const noexcept { return histogram_.snapshot(); }

  // Not real-time. What prepare_realtime_thread() achieved on the loop
  // thread; valid once start() has returned (empty before, and for
  // run_for_ticks()).
  const RtSetupReport& setup_report() const noexcept { return report_; }
  const RtOptions& options() const noexcept { return options_; }

 private:
  void thread_main(TickFn fn, void* ctx) noexcept;
  void begin_schedule() noexcept;
  void cycle(TickFn fn, void* ctx) noexcept;

  const RtOptions options_;
  Clock& clock_;
  const Nanos period_;
  const Nanos threshold_;

  // Loop state: touched only by whichever thread runs the loop.
  Nanos next_{0};
  std::uint64_t index_ = 0;
  bool late_finish_ = false;
  bool scheduled_ = false;

  // Shared with other threads.
  std::atomic<bool> stop_{false};
  std::atomic<bool> running_{false};
  std::atomic<bool> ready_{false};
  std::atomic<bool> force_overrun_{false};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> missed_{0};
  std::atomic<std::int64_t> max_tick_ns_{0};
  LatencyHistogram histogram_;
  RtSetupReport report_;
  std::thread thread_;
};

}  // namespace smc::edge::rt
