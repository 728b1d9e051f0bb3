#include "smc/edge/rt/double_buffer.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <thread>

#include "alloc_counter.hpp"
#include "smc/common/clock.hpp"
#include "smc/edge/rt/rt_loop.hpp"

namespace smc::edge::rt {
namespace {

// Records where each configuration dies, and catches use after free: every
// value equals the generation while the object is alive.
struct Deaths {
  std::atomic<int> count{0};
  std::atomic<int> on_rt_thread{0};
  std::atomic<std::thread::id> rt_thread{};
};

struct Config {
  Config(int gen, Deaths* d) : generation(gen), deaths(d) { values.fill(gen); }
  ~Config() {
    deaths->count.fetch_add(1);
    if (std::this_thread::get_id() == deaths->rt_thread.load()) deaths->on_rt_thread.fetch_add(1);
    values.fill(-1);
  }
  bool consistent() const {
    for (int v : values) {
      if (v != generation) return false;
    }
    return true;
  }
  int generation;
  std::array<int, 64> values{};
  Deaths* deaths;
};

TEST(DoubleBuffer, NewObjectIsSeenOnlyAtTakePending) {
  Deaths deaths;
  DoubleBuffer<Config> buf(std::make_unique<const Config>(0, &deaths));
  EXPECT_EQ(buf.current().generation, 0);
  EXPECT_FALSE(buf.has_pending());
  EXPECT_FALSE(buf.take_pending());

  ASSERT_TRUE(buf.publish(std::make_unique<const Config>(1, &deaths)));
  EXPECT_TRUE(buf.has_pending());
  EXPECT_EQ(buf.current().generation, 0);  // not before the boundary
  EXPECT_TRUE(buf.take_pending());
  EXPECT_EQ(buf.current().generation, 1);
  EXPECT_FALSE(buf.has_pending());
  EXPECT_FALSE(buf.take_pending());
  EXPECT_EQ(buf.swaps(), 1u);

  // The old one is alive until the writer reclaims it.
  EXPECT_EQ(deaths.count.load(), 0);
  EXPECT_EQ(buf.reclaim(), 1u);
  EXPECT_EQ(deaths.count.load(), 1);
  EXPECT_EQ(buf.reclaim(), 0u);
}

TEST(DoubleBuffer, UnseenObjectIsReplacedAndDeletedByTheWriter) {
  Deaths deaths;
  DoubleBuffer<Config> buf(std::make_unique<const Config>(0, &deaths));
  buf.publish(std::make_unique<const Config>(1, &deaths));
  buf.publish(std::make_unique<const Config>(2, &deaths));
  EXPECT_EQ(deaths.count.load(), 1);  // generation 1, never seen
  EXPECT_TRUE(buf.take_pending());
  EXPECT_EQ(buf.current().generation, 2);
  EXPECT_EQ(buf.swaps(), 1u);
  EXPECT_FALSE(buf.publish(nullptr));
}

TEST(DoubleBuffer, DestructorFreesEverything) {
  Deaths deaths;
  {
    DoubleBuffer<Config> buf(std::make_unique<const Config>(0, &deaths));
    buf.publish(std::make_unique<const Config>(1, &deaths));
    buf.take_pending();                                       // 0 retired
    buf.publish(std::make_unique<const Config>(2, &deaths));  // reclaims 0; 2 pending
  }
  EXPECT_EQ(deaths.count.load(), 3);
  EXPECT_THROW(DoubleBuffer<Config>(nullptr), std::invalid_argument);
}

TEST(DoubleBuffer, TakePendingDoesNotAllocateOrFree) {
  Deaths deaths;
  DoubleBuffer<Config> buf(std::make_unique<const Config>(0, &deaths));
  buf.publish(std::make_unique<const Config>(1, &deaths));
  test::AllocationCounter counter;
  {
    test::ForbidAllocations guard;
    EXPECT_TRUE(buf.take_pending());
    EXPECT_EQ(buf.current().generation, 1);
    EXPECT_EQ(guard.violations(), 0u);
  }
  EXPECT_EQ(counter.deallocations(), 0u);
  EXPECT_EQ(deaths.count.load(), 0);
}

// A configuration published between cycles is in use from the next tick of
// the loop on: with a VirtualClock the boundary is exact.
struct SwapTick {
  DoubleBuffer<Config>* buf = nullptr;
  int seen[64] = {};
  std::uint64_t n = 0;
};

void swap_tick(void* ctx, const TickInfo& info) noexcept {
  auto* t = static_cast<SwapTick*>(ctx);
  t->buf->take_pending();  // cycle boundary
  t->seen[info.index % 64] = t->buf->current().generation;
  ++t->n;
}

TEST(DoubleBuffer, LoopSeesNewConfigAtNextCycleBoundary) {
  Deaths deaths;
  DoubleBuffer<Config> buf(std::make_unique<const Config>(0, &deaths));
  VirtualClock clock;
  RtLoop loop({.priority = 0, .lock_memory = false}, clock);
  SwapTick t;
  t.buf = &buf;
  loop.run_for_ticks(3, swap_tick, &t);
  buf.publish(std::make_unique<const Config>(7, &deaths));
  loop.run_for_ticks(2, swap_tick, &t);
  EXPECT_EQ(t.seen[2], 0);
  EXPECT_EQ(t.seen[3], 7);
  EXPECT_EQ(t.seen[4], 7);
  EXPECT_EQ(buf.reclaim(), 1u);
}

// Writer and real-time side on two threads: the real-time side always sees
// a whole, live object, generations never go back, and no object dies on the
// real-time thread. The real-time side runs under ForbidAllocations.
TEST(DoubleBuffer, TwoThreadsNoTearingNoFreeOnRtThread) {
  constexpr int kPublishes = 20'000;
  Deaths deaths;
  auto buf = std::make_unique<DoubleBuffer<Config>>(std::make_unique<const Config>(0, &deaths));
  std::atomic<bool> writer_done{false};
  std::atomic<std::uint64_t> violations{~0ull};
  std::atomic<int> bad{0};
  std::atomic<int> last_seen{0};

  std::thread rt([&] {
    deaths.rt_thread.store(std::this_thread::get_id());
    std::uint64_t v = 0;
    {
      test::ForbidAllocations guard;
      int last = 0;
      for (;;) {
        const bool finished = writer_done.load(std::memory_order_acquire);
        buf->take_pending();
        const Config& c = buf->current();
        if (!c.consistent() || c.generation < last) bad.fetch_add(1);
        last = c.generation;
        if (finished && !buf->has_pending()) break;
      }
      last_seen.store(last);
      v = guard.violations();
    }
    violations.store(v);
  });

  for (int g = 1; g <= kPublishes; ++g) {
    buf->publish(std::make_unique<const Config>(g, &deaths));
    if (g % 64 == 0) std::this_thread::yield();
  }
  writer_done.store(true, std::memory_order_release);
  rt.join();
  buf->reclaim();

  EXPECT_EQ(bad.load(), 0);
  EXPECT_EQ(violations.load(), 0u);
  EXPECT_EQ(last_seen.load(), kPublishes);  // the last publish is always taken
  EXPECT_EQ(deaths.on_rt_thread.load(), 0);
  // Everything but the current object is gone already.
  EXPECT_EQ(deaths.count.load(), kPublishes);
  buf.reset();
  EXPECT_EQ(deaths.count.load(), kPublishes + 1);
}

}  // namespace
}  // namespace smc::edge::rt
