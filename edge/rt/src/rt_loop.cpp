#include "smc/edge/rt/rt_loop.hpp"

#include <stdexcept>

namespace smc::edge::rt {

RtLoop::RtLoop(const RtOptions& options, Clock& clock)
    : options_(options),
      clock_(clock),
      period_(options.period),
      threshold_(effective_overrun_threshold(options)) {
  if (period_ <= Nanos{0}) throw std::invalid_argument("RtLoop: period must be positive");
}

RtLoop::~RtLoop() { stop(); }

void RtLoop::start(TickFn fn, void* ctx) {
  if (fn == nullptr) throw std::invalid_argument("RtLoop::start: no tick function");
  if (running()) throw std::logic_error("RtLoop::start: already running");
  if (thread_.joinable()) thread_.join();  // ended by request_stop()
  stop_.store(false, std::memory_order_release);
  ready_.store(false, std::memory_order_release);
  report_ = RtSetupReport{};
  running_.store(true, std::memory_order_release);
  try {
    thread_ = std::thread(&RtLoop::thread_main, this, fn, ctx);
  } catch (...) {
    running_.store(false, std::memory_order_release);
    throw;
  }
  ready_.wait(false, std::memory_order_acquire);
}

void RtLoop::stop() {
  request_stop();
  if (thread_.joinable()) thread_.join();
}

void RtLoop::run_for_ticks(std::uint64_t n, TickFn fn, void* ctx) {
  if (fn == nullptr) throw std::invalid_argument("RtLoop::run_for_ticks: no tick function");
  if (running()) throw std::logic_error("RtLoop::run_for_ticks: the loop thread is running");
  stop_.store(false, std::memory_order_release);
  if (!scheduled_) begin_schedule();
  for (std::uint64_t i = 0; i < n && !stop_.load(std::memory_order_acquire); ++i) {
    cycle(fn, ctx);
  }
}

void RtLoop::thread_main(TickFn fn, void* ctx) noexcept {
  // Start-up: may allocate (the report's notes), lock, take page faults.
  report_ = prepare_realtime_thread(options_);
  begin_schedule();
  ready_.store(true, std::memory_order_release);
  ready_.notify_all();
  // From here on: no allocation, no lock, no logging.
  while (!stop_.load(std::memory_order_acquire)) cycle(fn, ctx);
  running_.store(false, std::memory_order_release);
}

void RtLoop::begin_schedule() noexcept {
  next_ = clock_.now() + period_;
  late_finish_ = false;
  scheduled_ = true;
}

void RtLoop::cycle(TickFn fn, void* ctx) noexcept {
  clock_.sleep_until(next_);
  const Nanos woke = clock_.now();
  const Nanos lateness = woke - next_;

  bool overrun = late_finish_ || lateness > threshold_;
  late_finish_ = false;
  if (force_overrun_.load(std::memory_order_relaxed) &&
      force_overrun_.exchange(false, std::memory_order_acq_rel)) {
    overrun = true;
  }
  histogram_.record(lateness);
  if (overrun) {
    overruns_.store(overruns_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  const TickInfo info{index_, next_, woke, lateness, overrun};
  fn(ctx, info);
  ++index_;
  ticks_.store(ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_release);

  const Nanos done = clock_.now();
  const std::int64_t took = (done - woke).count();
  if (took > max_tick_ns_.load(std::memory_order_relaxed)) {
    max_tick_ns_.store(took, std::memory_order_relaxed);
  }

  // The deadline of this tick is the next boundary. Past it: skip to the
  // first boundary still ahead, do not burst. The next tick carries the
  // overrun unless this one already did because it woke past that deadline
  // (one stall, one flag).
  const Nanos deadline = next_ + period_;
  next_ = deadline;
  if (done > deadline) {
    const std::int64_t behind = (done - deadline) / period_ + 1;
    next_ += behind * period_;
    missed_.store(missed_.load(std::memory_order_relaxed) + static_cast<std::uint64_t>(behind),
                  std::memory_order_release);
    late_finish_ = !(overrun && woke > deadline);
  }
}

}  // namespace smc::edge::rt
