#include "smc/edge/rt/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "alloc_counter.hpp"

namespace smc::edge::rt {
namespace {

struct Item {
  std::uint64_t seq = 0;
  std::uint64_t check = 0;  // derived from seq: a torn or stale slot shows
  double payload[6] = {};
};

Item make_item(std::uint64_t seq) {
  Item it;
  it.seq = seq;
  it.check = seq * 0x9E3779B97F4A7C15ull + 1;
  for (int i = 0; i < 6; ++i) it.payload[i] = static_cast<double>(seq) + i;
  return it;
}

bool intact(const Item& it) {
  if (it.check != it.seq * 0x9E3779B97F4A7C15ull + 1) return false;
  for (int i = 0; i < 6; ++i) {
    if (it.payload[i] != static_cast<double>(it.seq) + i) return false;
  }
  return true;
}

TEST(SpscRing, StartsEmpty) {
  SpscRing<int, 4> ring;
  int out = 7;
  EXPECT_EQ(ring.capacity(), 4u);
  EXPECT_EQ(ring.size_approx(), 0u);
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(out, 7);  // untouched
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST(SpscRing, FifoOrderAndFullRingDrops) {
  SpscRing<int, 4> ring;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i)) << i;
  EXPECT_EQ(ring.size_approx(), 4u);
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_FALSE(ring.try_push(100));
  EXPECT_EQ(ring.dropped(), 2u);
  EXPECT_EQ(ring.size_approx(), 4u);
  int out = -1;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(ring.size_approx(), 0u);
  EXPECT_EQ(ring.dropped(), 2u);  // drops are not forgotten
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<std::uint32_t, 8> ring;
  std::uint32_t expect = 0;
  std::uint32_t next = 0;
  for (int round = 0; round < 1000; ++round) {
    // Uneven batches so head and tail cross the wrap at every offset.
    const int push = 1 + round % 8;
    for (int i = 0; i < push; ++i) {
      if (ring.try_push(next)) ++next;
    }
    const int pop = 1 + (round * 5) % 8;
    std::uint32_t out = 0;
    for (int i = 0; i < pop && ring.try_pop(out); ++i) {
      ASSERT_EQ(out, expect);
      ++expect;
    }
    ASSERT_LE(ring.size_approx(), 8u);
    ASSERT_EQ(ring.size_approx(), next - expect);
  }
}

TEST(SpscRing, PushAndPopDoNotAllocate) {
  SpscRing<Item, 64> ring;  // allocates its slots here, once
  test::ForbidAllocations guard;
  Item out;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    ring.try_push(make_item(i));
    if (i % 3 == 0) ring.try_pop(out);
  }
  EXPECT_EQ(guard.violations(), 0u);
}

// The producer retries when the ring is full, so nothing may be lost: the
// consumer must see 0, 1, 2, ... N-1, each intact.
TEST(SpscRing, TwoThreadsInOrderWithoutLoss) {
  constexpr std::uint64_t kItems = 1'000'000;
  SpscRing<Item, 1024> ring;
  std::uint64_t refused = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      const Item it = make_item(i);
      while (!ring.try_push(it)) {
        ++refused;
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expect = 0;
  std::uint64_t bad = 0;
  Item out;
  while (expect < kItems) {
    if (!ring.try_pop(out)) {
      std::this_thread::yield();
      continue;
    }
    if (out.seq != expect || !intact(out)) ++bad;
    expect = out.seq + 1;
  }
  producer.join();
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(expect, kItems);
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(ring.dropped(), refused);  // every refusal counted, nothing else
}

// A producer that never waits (the real-time side): what the consumer gets
// is strictly increasing and intact, and received + dropped = pushed.
TEST(SpscRing, TwoThreadsDropsAreCountedExactly) {
  constexpr std::uint64_t kItems = 1'000'000;
  SpscRing<Item, 64> ring;
  std::atomic<bool> done{false};
  std::uint64_t accepted = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      if (ring.try_push(make_item(i))) ++accepted;
    }
    done.store(true, std::memory_order_release);
  });
  std::uint64_t received = 0;
  std::uint64_t bad = 0;
  std::uint64_t last = 0;
  bool first = true;
  Item out;
  for (;;) {
    if (ring.try_pop(out)) {
      if (!intact(out) || (!first && out.seq <= last)) ++bad;
      last = out.seq;
      first = false;
      ++received;
      continue;
    }
    if (done.load(std::memory_order_acquire)) {
      // Drain what was pushed before `done`.
      while (ring.try_pop(out)) {
        if (!intact(out) || (!first && out.seq <= last)) ++bad;
        last = out.seq;
        first = false;
        ++received;
      }
      break;
    }
    std::this_thread::yield();
  }
  producer.join();
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(received, accepted);
  EXPECT_EQ(received + ring.dropped(), kItems);
}

}  // namespace
}  // namespace smc::edge::rt
