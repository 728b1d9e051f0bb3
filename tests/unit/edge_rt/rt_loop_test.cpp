// RtLoop against a VirtualClock: deterministic schedule, overrun delivery,
// skipping instead of bursting. No sleeps: VirtualClock::sleep_until jumps.

#include "smc/edge/rt/rt_loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "smc/common/clock.hpp"

namespace smc::edge::rt {
namespace {

using namespace std::chrono_literals;

constexpr Nanos kPeriod = 500us;
constexpr Nanos kStart = 1s;

RtOptions virtual_options() {
  RtOptions o;
  o.priority = 0;  // a thread that never really sleeps must not run SCHED_FIFO
  o.lock_memory = false;
  return o;
}

// What a tick saw, and optionally what it does to the clock.
struct Recorder {
  VirtualClock* clock = nullptr;
  std::vector<TickInfo> infos;  // reserved before the run
  // Tick index -> how long that tick "takes" (advances the virtual clock).
  std::uint64_t slow_index = ~0ull;
  Nanos slow_by{0};
  std::uint64_t stop_after = ~0ull;
  RtLoop* loop = nullptr;
};

void record_tick(void* ctx, const TickInfo& info) noexcept {
  auto* r = static_cast<Recorder*>(ctx);
  if (r->infos.size() < r->infos.capacity()) r->infos.push_back(info);
  if (info.index == r->slow_index) r->clock->advance(r->slow_by);
  if (r->loop != nullptr && info.index + 1 >= r->stop_after) r->loop->request_stop();
}

TEST(RtLoop, TicksAtExactPeriodBoundaries) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(100);
  loop.run_for_ticks(100, record_tick, &r);

  ASSERT_EQ(r.infos.size(), 100u);
  for (std::uint64_t i = 0; i < 100; ++i) {
    const TickInfo& t = r.infos[i];
    EXPECT_EQ(t.index, i);
    EXPECT_EQ(t.scheduled, kStart + kPeriod * static_cast<std::int64_t>(i + 1));
    EXPECT_EQ(t.woke, t.scheduled);
    EXPECT_EQ(t.lateness, Nanos{0});
    EXPECT_FALSE(t.overrun);
  }
  EXPECT_EQ(loop.ticks(), 100u);
  EXPECT_EQ(loop.overruns(), 0u);
  EXPECT_EQ(loop.missed_periods(), 0u);
  const LatencySnapshot lat = loop.latency();
  EXPECT_EQ(lat.count(), 100u);
  EXPECT_EQ(lat.max(), Nanos{0});
  EXPECT_EQ(lat.percentile(0.99), Nanos{0});
}

TEST(RtLoop, RunForTicksContinuesTheSchedule) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(10);
  loop.run_for_ticks(4, record_tick, &r);
  loop.run_for_ticks(6, record_tick, &r);
  ASSERT_EQ(r.infos.size(), 10u);
  EXPECT_EQ(r.infos[9].index, 9u);
  EXPECT_EQ(r.infos[9].scheduled, kStart + 10 * kPeriod);
  EXPECT_EQ(loop.ticks(), 10u);
}

// A tick that runs 1.5 periods: the next boundary is skipped (no burst),
// the tick after carries overrun, and only that one.
TEST(RtLoop, TickPastDeadlineFlagsNextTickAndSkips) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(10);
  r.slow_index = 5;
  r.slow_by = kPeriod + kPeriod / 2;
  loop.run_for_ticks(10, record_tick, &r);

  ASSERT_EQ(r.infos.size(), 10u);
  for (std::uint64_t i = 0; i < 10; ++i) {
    EXPECT_EQ(r.infos[i].overrun, i == 6) << "tick " << i;
    EXPECT_EQ(r.infos[i].lateness, Nanos{0}) << "tick " << i;
  }
  // Tick 5 was due at start + 6P and ended at start + 7.5P: tick 6 runs at
  // the first boundary after that, start + 8P, one boundary (7P) skipped.
  EXPECT_EQ(r.infos[5].scheduled, kStart + 6 * kPeriod);
  EXPECT_EQ(r.infos[6].scheduled, kStart + 8 * kPeriod);
  EXPECT_EQ(r.infos[7].scheduled, kStart + 9 * kPeriod);
  EXPECT_EQ(loop.overruns(), 1u);
  EXPECT_EQ(loop.missed_periods(), 1u);
  EXPECT_EQ(loop.max_tick_duration(), r.slow_by);
}

TEST(RtLoop, LongStallSkipsEveryMissedBoundary) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(4);
  r.slow_index = 0;
  r.slow_by = kPeriod * 32 / 10;  // 3.2 periods
  loop.run_for_ticks(3, record_tick, &r);
  // Tick 0 due at 1P, ends at 4.2P: boundaries 2P, 3P, 4P are gone.
  EXPECT_EQ(r.infos[1].scheduled, kStart + 5 * kPeriod);
  EXPECT_TRUE(r.infos[1].overrun);
  EXPECT_FALSE(r.infos[2].overrun);
  EXPECT_EQ(loop.missed_periods(), 3u);
  EXPECT_EQ(loop.overruns(), 1u);
}

TEST(RtLoop, TickUsingExactlyOnePeriodIsNotAnOverrun) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(3);
  r.slow_index = 0;
  r.slow_by = kPeriod;  // ends exactly at its deadline
  loop.run_for_ticks(3, record_tick, &r);
  EXPECT_FALSE(r.infos[1].overrun);
  EXPECT_EQ(r.infos[1].scheduled, kStart + 2 * kPeriod);
  EXPECT_EQ(loop.overruns(), 0u);
}

TEST(RtLoop, ForcedOverrunIsDeliveredOnceAndCounted) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.infos.reserve(6);
  loop.run_for_ticks(2, record_tick, &r);
  loop.force_overrun();
  loop.run_for_ticks(3, record_tick, &r);
  ASSERT_EQ(r.infos.size(), 5u);
  EXPECT_FALSE(r.infos[1].overrun);
  EXPECT_TRUE(r.infos[2].overrun);
  EXPECT_FALSE(r.infos[3].overrun);
  EXPECT_EQ(loop.overruns(), 1u);
  EXPECT_EQ(loop.missed_periods(), 0u);  // nothing was really late
}

// A clock whose sleeps overshoot: lateness and the wake-up threshold.
class LateClock final : public Clock {
 public:
  Nanos now() const noexcept override { return Nanos{now_.load()}; }
  void sleep_until(Nanos deadline) noexcept override {
    if (deadline.count() > now_.load()) now_.store(deadline.count() + late_.load());
  }
  void set_late(Nanos l) noexcept { late_.store(l.count()); }

 private:
  std::atomic<std::int64_t> now_{0};
  std::atomic<std::int64_t> late_{0};
};

void noop_tick(void*, const TickInfo&) noexcept {}

struct LateRecorder {
  LateClock* clock = nullptr;
  std::vector<TickInfo> infos;
};

void late_tick(void* ctx, const TickInfo& info) noexcept {
  auto* r = static_cast<LateRecorder*>(ctx);
  if (r->infos.size() < r->infos.capacity()) r->infos.push_back(info);
}

TEST(RtLoop, WakeUpLaterThanThresholdIsAnOverrun) {
  LateClock clock;
  RtOptions o = virtual_options();
  o.overrun_threshold = 50us;
  RtLoop loop(o, clock);
  LateRecorder r;
  r.clock = &clock;
  r.infos.reserve(4);
  clock.set_late(30us);
  loop.run_for_ticks(2, late_tick, &r);
  clock.set_late(120us);
  loop.run_for_ticks(1, late_tick, &r);
  clock.set_late(0us);
  loop.run_for_ticks(1, late_tick, &r);

  ASSERT_EQ(r.infos.size(), 4u);
  EXPECT_EQ(r.infos[0].lateness, 30us);
  EXPECT_FALSE(r.infos[0].overrun);
  EXPECT_FALSE(r.infos[1].overrun);
  EXPECT_EQ(r.infos[2].lateness, 120us);
  EXPECT_TRUE(r.infos[2].overrun);
  EXPECT_FALSE(r.infos[3].overrun);
  EXPECT_EQ(loop.overruns(), 1u);

  const LatencySnapshot lat = loop.latency();
  EXPECT_EQ(lat.count(), 4u);
  EXPECT_EQ(lat.max(), 120us);
  EXPECT_EQ(lat.bucket_count(30), 2u);
  EXPECT_EQ(lat.bucket_count(120), 1u);
  EXPECT_EQ(lat.bucket_count(0), 1u);
}

// A wake-up more than a period late passes the next boundary by itself:
// that tick is flagged, the boundary is skipped, and the tick after is not
// flagged again for the same stall.
TEST(RtLoop, WakeUpPastNextBoundaryIsOneOverrun) {
  LateClock clock;
  RtLoop loop(virtual_options(), clock);  // threshold: one period
  LateRecorder r;
  r.clock = &clock;
  r.infos.reserve(3);
  loop.run_for_ticks(1, late_tick, &r);
  clock.set_late(kPeriod + 200us);
  loop.run_for_ticks(1, late_tick, &r);
  clock.set_late(0us);
  loop.run_for_ticks(1, late_tick, &r);

  ASSERT_EQ(r.infos.size(), 3u);
  EXPECT_FALSE(r.infos[0].overrun);
  EXPECT_TRUE(r.infos[1].overrun);
  EXPECT_EQ(r.infos[1].lateness, kPeriod + 200us);
  EXPECT_FALSE(r.infos[2].overrun);
  EXPECT_EQ(r.infos[2].scheduled - r.infos[1].scheduled, 2 * kPeriod);
  EXPECT_EQ(r.infos[2].lateness, Nanos{0});
  EXPECT_EQ(loop.overruns(), 1u);
  EXPECT_EQ(loop.missed_periods(), 1u);
}

TEST(RtLoop, DefaultThresholdIsOnePeriod) {
  RtOptions o;
  EXPECT_EQ(effective_overrun_threshold(o), o.period);
  o.period = 1ms;
  EXPECT_EQ(effective_overrun_threshold(o), 1ms);
  o.overrun_threshold = 200us;
  EXPECT_EQ(effective_overrun_threshold(o), 200us);
}

TEST(RtLoop, RequestStopFromTickEndsRunForTicks) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder r;
  r.clock = &clock;
  r.loop = &loop;
  r.stop_after = 7;
  r.infos.reserve(100);
  loop.run_for_ticks(100, record_tick, &r);
  EXPECT_EQ(loop.ticks(), 7u);
}

TEST(RtLoop, RejectsBadArguments) {
  VirtualClock clock;
  RtOptions o = virtual_options();
  o.period = Nanos{0};
  EXPECT_THROW(RtLoop(o, clock), std::invalid_argument);
  RtLoop loop(virtual_options(), clock);
  EXPECT_THROW(loop.run_for_ticks(1, nullptr, nullptr), std::invalid_argument);
  EXPECT_THROW(loop.start(nullptr, nullptr), std::invalid_argument);
}

// Waits for a loop that stops itself (request_stop() from a tick). A
// condition with a generous deadline, not a timed guess.
bool wait_until_stopped(const RtLoop& loop, std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (loop.running()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

// The same loop on its own thread, still on a VirtualClock. start() while
// running is refused; stop() joins; a loop that ended may start again and
// its indices continue.
TEST(RtLoop, ThreadModeRunsAndStops) {
  VirtualClock clock(kStart);
  RtLoop loop(virtual_options(), clock);
  Recorder forever;
  forever.clock = &clock;
  forever.infos.reserve(0);
  loop.start(record_tick, &forever);
  EXPECT_TRUE(loop.running());
  EXPECT_THROW(loop.start(noop_tick, nullptr), std::logic_error);
  EXPECT_THROW(loop.run_for_ticks(1, noop_tick, nullptr), std::logic_error);
  EXPECT_NE(loop.setup_report().notes.find("SCHED_FIFO: not requested"), std::string::npos)
      << loop.setup_report().notes;
  loop.stop();
  EXPECT_FALSE(loop.running());
  loop.stop();  // idempotent

  const std::uint64_t before = loop.ticks();
  Recorder r;
  r.clock = &clock;
  r.loop = &loop;
  r.stop_after = before + 1000;
  r.infos.reserve(1000);
  loop.start(record_tick, &r);
  ASSERT_TRUE(wait_until_stopped(loop, 30s));
  loop.stop();
  EXPECT_EQ(loop.ticks(), before + 1000);
  ASSERT_EQ(r.infos.size(), 1000u);
  for (std::size_t i = 0; i < r.infos.size(); ++i) {
    ASSERT_EQ(r.infos[i].index, before + i);
    ASSERT_FALSE(r.infos[i].overrun);
    if (i > 0) {
      ASSERT_EQ(r.infos[i].scheduled - r.infos[i - 1].scheduled, kPeriod);
    }
  }
}

}  // namespace
}  // namespace smc::edge::rt
