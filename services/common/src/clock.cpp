#include "smc/common/clock.hpp"

#include <cerrno>
#include <ctime>

namespace smc {

Nanos RealClock::now() const noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return Nanos{int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec};
}

void RealClock::sleep_until(Nanos deadline) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(deadline.count() % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void VirtualClock::sleep_until(Nanos deadline) noexcept {
  int64_t cur = now_.load(std::memory_order_acquire);
  while (deadline.count() > cur &&
         !now_.compare_exchange_weak(cur, deadline.count(), std::memory_order_acq_rel)) {
  }
}

int64_t unix_time_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace smc
