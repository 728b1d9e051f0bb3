// RtLoop on the wall clock for ~200 ms (400 ticks at 500 µs), with the real
// set-up. The machine is shared and noisy: nothing here asserts a latency
// bound, only invariants that hold however late the wake-ups are.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include "smc/common/clock.hpp"
#include "smc/edge/rt/rt_loop.hpp"
#include "smc/edge/rt/rt_setup.hpp"

namespace smc::edge::rt {
namespace {

using namespace std::chrono_literals;

constexpr std::uint64_t kTicks = 400;
constexpr std::uint64_t kSpinTick = 100;

struct Ctx {
  Clock* clock = nullptr;
  RtLoop* loop = nullptr;
  std::vector<TickInfo> infos;  // reserved: push_back never allocates
};

void tick(void* p, const TickInfo& info) noexcept {
  auto* c = static_cast<Ctx*>(p);
  c->infos.push_back(info);
  if (info.index == kSpinTick) {
    // Run past the deadline for real: 2.5 periods.
    const Nanos until = info.scheduled + c->loop->options().period * 5 / 2;
    while (c->clock->now() < until) {
    }
  }
  if (c->infos.size() == kTicks) c->loop->request_stop();
}

TEST(RtWallClock, TicksHistogramAndARealOverrun) {
  RealClock clock;
  const RtOptions opts;  // 500 µs, SCHED_FIFO 80 and mlockall when permitted
  const Nanos period = opts.period;
  RtLoop loop(opts, clock);
  Ctx ctx;
  ctx.clock = &clock;
  ctx.loop = &loop;
  ctx.infos.reserve(kTicks);

  loop.start(tick, &ctx);
  const RtSetupReport& rep = loop.setup_report();
  std::printf("set-up: %s\n%s\n", summary(rep, opts).c_str(), rep.notes.c_str());
  EXPECT_FALSE(rep.notes.empty());
  if (rep.sched_fifo) {
    EXPECT_EQ(rep.priority, opts.priority);
  }
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (loop.running() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_FALSE(loop.running()) << "400 ticks took more than 60 s";
  loop.stop();

  ASSERT_EQ(ctx.infos.size(), kTicks);
  EXPECT_EQ(loop.ticks(), kTicks);
  std::uint64_t flagged = 0;
  for (std::size_t i = 0; i < kTicks; ++i) {
    const TickInfo& t = ctx.infos[i];
    ASSERT_EQ(t.index, i);
    ASSERT_GE(t.lateness, Nanos{0});
    ASSERT_EQ(t.woke - t.scheduled, t.lateness);
    if (t.overrun) ++flagged;
    if (i > 0) {
      const Nanos step = t.scheduled - ctx.infos[i - 1].scheduled;
      ASSERT_GE(step, period);
      ASSERT_EQ(step % period, Nanos{0}) << "tick " << i << " off the period grid";
    }
  }
  // The spinning tick ended at least 2.5 periods after it was due, so at
  // least two boundaries were skipped and the stall is flagged once: on the
  // tick after it -- or on the spinning tick itself, when the machine woke
  // it past its own deadline already (one stall, one flag:
  // RtLoop.WakeUpPastNextBoundaryIsOneOverrun). Checking the tick after
  // only, a run under load failed: 1 overrun, 2 missed periods, a wake-up
  // of 534 us at 500 us.
  const TickInfo& spin = ctx.infos[kSpinTick];
  const bool flagged_itself = spin.overrun && spin.woke > spin.scheduled + period;
  EXPECT_TRUE(flagged_itself || ctx.infos[kSpinTick + 1].overrun)
      << "the spinning tick woke " << spin.lateness.count() << " ns late";
  EXPECT_GE(ctx.infos[kSpinTick + 1].scheduled - ctx.infos[kSpinTick].scheduled, 3 * period);
  EXPECT_GE(loop.missed_periods(), 2u);
  EXPECT_EQ(loop.overruns(), flagged);
  EXPECT_GE(loop.max_tick_duration(), period * 5 / 2 - ctx.infos[kSpinTick].lateness);
  // No catch-up burst: the grid from first to last tick holds every tick
  // and every skipped boundary, nothing else.
  const Nanos span = ctx.infos.back().scheduled - ctx.infos.front().scheduled;
  EXPECT_EQ(span / period, static_cast<std::int64_t>(kTicks - 1 + loop.missed_periods()));

  const LatencySnapshot lat = loop.latency();
  EXPECT_EQ(lat.count(), kTicks);
  EXPECT_LE(lat.percentile(0.5), lat.percentile(0.99));
  EXPECT_LE(lat.percentile(0.99), lat.max());
  std::printf(
      "wake-up latency over %llu ticks: p50 %lld us, p99 %lld us, max %lld us; "
      "overruns %llu, missed periods %llu\n",
      static_cast<unsigned long long>(lat.count()),
      static_cast<long long>(lat.percentile(0.5).count() / 1000),
      static_cast<long long>(lat.percentile(0.99).count() / 1000),
      static_cast<long long>(lat.max().count() / 1000),
      static_cast<unsigned long long>(loop.overruns()),
      static_cast<unsigned long long>(loop.missed_periods()));
}

// Each refused step is reported and skipped; nothing is fatal. Runs on its
// own thread so that this test's thread keeps its scheduling.
TEST(RtSetup, RefusedStepsAreNotedNotFatal) {
  RtSetupReport rep;
  std::thread t([&] {
    RtOptions o;
    o.priority = 200;  // outside 1..99
    o.cpu = 100'000;   // no such CPU
    o.lock_memory = false;
    o.stack_prefault_bytes = 64 * 1024;
    rep = prepare_realtime_thread(o);
  });
  t.join();
  EXPECT_FALSE(rep.sched_fifo);
  EXPECT_EQ(rep.priority, 0);
  EXPECT_FALSE(rep.affinity);
  EXPECT_FALSE(rep.memory_locked);
  EXPECT_TRUE(rep.stack_prefaulted);
  EXPECT_NE(rep.notes.find("priority 200 outside"), std::string::npos) << rep.notes;
  EXPECT_NE(rep.notes.find("cpu 100000"), std::string::npos) << rep.notes;
  EXPECT_NE(rep.notes.find("mlockall: not requested"), std::string::npos) << rep.notes;
}

TEST(RtSetup, PinsToAnAllowedCpu) {
  RtSetupReport rep;
  int ran_on = -1;
  std::thread t([&] {
    RtOptions o;
    o.priority = 0;
    o.lock_memory = false;
    o.cpu = 0;
    rep = prepare_realtime_thread(o);
    ran_on = sched_getcpu();
  });
  t.join();
  // CPU 0 may be outside a restricted cpuset; then the note says so.
  if (rep.affinity) {
    EXPECT_EQ(ran_on, 0);
  } else {
    EXPECT_NE(rep.notes.find("affinity cpu 0:"), std::string::npos) << rep.notes;
  }
}

}  // namespace
}  // namespace smc::edge::rt
