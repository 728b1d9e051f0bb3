#pragma once
// Time for everything that is stepped: a real monotonic clock for deployment
// and a manually advanced virtual clock for tests and offline simulation.

#include <atomic>
#include <chrono>
#include <cstdint>

namespace smc {

// Nanoseconds on a monotonic time line (machine time).
using Nanos = std::chrono::nanoseconds;

class Clock {
 public:
  virtual ~Clock() = default;
  // Real-time safe: no allocation, no lock.
  virtual Nanos now() const noexcept = 0;
  // Blocks (real clock) or jumps (virtual clock) until `deadline`.
  virtual void sleep_until(Nanos deadline) noexcept = 0;
};

// CLOCK_MONOTONIC; sleep_until uses clock_nanosleep with TIMER_ABSTIME.
class RealClock final : public Clock {
 public:
  Nanos now() const noexcept override;
  void sleep_until(Nanos deadline) noexcept override;
};

// Starts at `start` and moves only when advanced. sleep_until(t) sets the
// time to t if t is later, so a loop written against Clock runs as fast as
// the CPU allows and is deterministic.
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(Nanos start = Nanos{0}) : now_(start.count()) {}
  Nanos now() const noexcept override { return Nanos{now_.load(std::memory_order_acquire)}; }
  void sleep_until(Nanos deadline) noexcept override;
  void advance(Nanos dt) noexcept { now_.fetch_add(dt.count(), std::memory_order_acq_rel); }
  void set(Nanos t) noexcept { now_.store(t.count(), std::memory_order_release); }

 private:
  std::atomic<int64_t> now_;
};

// Wall-clock time (CLOCK_REALTIME) since the Unix epoch, for time stamps
// that leave the process (documents, logs, ids that must survive a
// restart). Never for stepping: use a Clock.
int64_t unix_time_ns() noexcept;
inline int64_t unix_time_ms() noexcept { return unix_time_ns() / 1'000'000; }

// Seconds as double, for the numerical code.
inline double to_seconds(Nanos t) noexcept { return static_cast<double>(t.count()) * 1e-9; }
inline Nanos from_seconds(double s) noexcept {
  return Nanos{static_cast<int64_t>(s * 1e9 + (s >= 0 ? 0.5 : -0.5))};
}

}  // namespace smc
