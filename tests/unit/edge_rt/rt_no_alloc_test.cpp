// The loop thread allocates and frees nothing after start-up: not in the
// loop's own code (sleep, clock, histogram, overrun accounting), nor in what
// a tick typically does with this library (take a new configuration at the
// boundary, push samples to a ring, read the latency snapshot). Counted with
// the replacement operator new of tests/support/alloc_counter.cpp, on the
// loop thread itself, from the first tick to the last.

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

#include "alloc_counter.hpp"
#include "smc/common/clock.hpp"
#include "smc/edge/rt/double_buffer.hpp"
#include "smc/edge/rt/rt_loop.hpp"
#include "smc/edge/rt/spsc_ring.hpp"

namespace smc::edge::rt {
namespace {

using namespace std::chrono_literals;

struct Config {
  int generation = 0;
  std::array<double, 32> gains{};
};

struct Sample {
  std::uint64_t index = 0;
  std::int64_t lateness_ns = 0;
  int generation = 0;
  bool overrun = false;
};

struct Ctx {
  RtLoop* loop = nullptr;
  DoubleBuffer<Config>* config = nullptr;
  SpscRing<Sample, 256>* samples = nullptr;
  std::uint64_t stop_after = 0;
  std::uint64_t allocate_at = ~0ull;  // proves the check can fail

  // Loop thread only.
  std::optional<test::ForbidAllocations> guard;
  test::AllocStats first{};
  std::uint64_t sink = 0;
  bool started = false;

  // Results, published when the tick stops the loop.
  std::atomic<bool> finished{false};
  std::uint64_t violations = ~0ull;
  std::uint64_t allocations = ~0ull;
  std::uint64_t deallocations = ~0ull;
  std::uint64_t ticks_guarded = 0;
};

void tick(void* ctx_ptr, const TickInfo& info) noexcept {
  auto* c = static_cast<Ctx*>(ctx_ptr);
  if (!c->started) {
    c->started = true;
    c->guard.emplace();  // optional::emplace of a guard: no allocation
    c->first = test::thread_alloc_stats();
  }
  c->config->take_pending();
  const Config& cfg = c->config->current();
  c->samples->try_push(Sample{info.index, info.lateness.count(), cfg.generation, info.overrun});
  if (info.index % 64 == 0) c->sink += c->loop->latency().count();
  if (info.index == c->allocate_at) {
    auto* p = new int(static_cast<int>(info.index));
    asm volatile("" : : "g"(p) : "memory");  // keep GCC from eliding the pair
    c->sink += static_cast<std::uint64_t>(*p);
    delete p;
  }
  ++c->ticks_guarded;
  if (c->ticks_guarded == c->stop_after) {
    const test::AllocStats last = test::thread_alloc_stats();
    c->violations = c->guard->violations();
    c->allocations = last.allocations - c->first.allocations;
    c->deallocations = last.deallocations - c->first.deallocations;
    c->guard.reset();
    c->loop->request_stop();
    c->finished.store(true, std::memory_order_release);
  }
}

struct Outcome {
  std::uint64_t violations, allocations, deallocations, ticks, received, dropped, swaps;
  RtSetupReport report;
};

// Runs the loop on its thread while this thread plays the comms and config
// side: drains samples, publishes configurations, forces an overrun now and
// then. Waits for the tick to stop the loop (bounded).
Outcome run(Clock& clock, const RtOptions& opts, std::uint64_t ticks, std::uint64_t allocate_at) {
  DoubleBuffer<Config> config(std::make_unique<const Config>());
  SpscRing<Sample, 256> samples;
  RtLoop loop(opts, clock);
  Ctx ctx;
  ctx.loop = &loop;
  ctx.config = &config;
  ctx.samples = &samples;
  ctx.stop_after = ticks;
  ctx.allocate_at = allocate_at;

  loop.start(tick, &ctx);
  std::uint64_t received = 0;
  int generation = 0;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  Sample s;
  while (!ctx.finished.load(std::memory_order_acquire) &&
         std::chrono::steady_clock::now() < deadline) {
    while (samples.try_pop(s)) ++received;
    if (received / 50 > static_cast<std::uint64_t>(generation)) {
      auto next = std::make_unique<Config>();
      next->generation = ++generation;
      config.publish(std::move(next));
      loop.force_overrun();
    }
    std::this_thread::sleep_for(200us);
  }
  loop.stop();
  while (samples.try_pop(s)) ++received;
  config.reclaim();
  EXPECT_TRUE(ctx.finished.load()) << "loop did not reach " << ticks << " ticks in 60 s";
  return {ctx.violations, ctx.allocations,   ctx.deallocations, loop.ticks(),
          received,       samples.dropped(), config.swaps(),    loop.setup_report()};
}

TEST(RtNoAlloc, LoopThreadAllocatesNothingVirtualClock) {
  VirtualClock clock;
  RtOptions opts;
  opts.priority = 0;  // never really sleeps: no SCHED_FIFO
  opts.lock_memory = false;
  const Outcome o = run(clock, opts, 200'000, ~0ull);
  EXPECT_EQ(o.violations, 0u);
  EXPECT_EQ(o.allocations, 0u);
  EXPECT_EQ(o.deallocations, 0u);
  EXPECT_EQ(o.ticks, 200'000u);
  EXPECT_EQ(o.received + o.dropped, o.ticks);
}

// Real sleeps (clock_nanosleep), real set-up (SCHED_FIFO and mlockall when
// permitted), 400 ticks at 500 µs.
TEST(RtNoAlloc, LoopThreadAllocatesNothingRealClock) {
  RealClock clock;
  const RtOptions opts;  // defaults: 500 µs, SCHED_FIFO 80, mlockall
  const Outcome o = run(clock, opts, 400, ~0ull);
  EXPECT_EQ(o.violations, 0u);
  EXPECT_EQ(o.allocations, 0u);
  EXPECT_EQ(o.deallocations, 0u);
  EXPECT_EQ(o.ticks, 400u);
  EXPECT_EQ(o.received + o.dropped, o.ticks);
  EXPECT_GE(o.swaps, 1u) << "no configuration swap happened during the run";
  std::printf("set-up: %s\n%s\n", summary(o.report, opts).c_str(), o.report.notes.c_str());
}

// The same check sees one allocation made in a tick: it can fail.
TEST(RtNoAlloc, CheckSeesAnAllocationInATick) {
  VirtualClock clock;
  RtOptions opts;
  opts.priority = 0;
  opts.lock_memory = false;
  const Outcome o = run(clock, opts, 1'000, 500);
  EXPECT_EQ(o.violations, 1u);
  EXPECT_EQ(o.allocations, 1u);
  EXPECT_EQ(o.deallocations, 1u);
}

TEST(AllocCounter, CountsThisThreadOnly) {
  test::AllocationCounter counter;
  std::uint64_t other_thread = 0;
  std::thread t([&] {
    test::AllocationCounter c;
    auto v = std::make_unique<std::array<char, 100>>();
    asm volatile("" : : "g"(v.get()) : "memory");
    other_thread = c.allocations();
  });
  t.join();
  EXPECT_EQ(other_thread, 1u);
  // std::thread itself allocates its state on this thread.
  const std::uint64_t before = counter.allocations();
  {
    auto p = std::make_unique<std::array<char, 100>>();
    asm volatile("" : : "g"(p.get()) : "memory");
  }
  EXPECT_EQ(counter.allocations() - before, 1u);
  EXPECT_GE(counter.bytes(), 100u);
  EXPECT_GE(test::process_alloc_stats().allocations, 2u);
}

TEST(AllocCounter, ForbidGuardsNest) {
  test::ForbidAllocations outer;
  {
    test::ForbidAllocations inner;
    auto p = std::make_unique<int>(1);
    asm volatile("" : : "g"(p.get()) : "memory");
    EXPECT_EQ(inner.violations(), 1u);
  }
  EXPECT_EQ(outer.violations(), 1u);
}

TEST(AllocCounterDeathTest, AbortModeAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        test::ForbidAllocations guard(test::ForbidAllocations::Mode::kAbort);
        auto p = std::make_unique<int>(1);
        asm volatile("" : : "g"(p.get()) : "memory");
      },
      "heap allocation on a thread under ForbidAllocations");
}

}  // namespace
}  // namespace smc::edge::rt
