#include "smc/edge/rt/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace smc::edge::rt {
namespace {

using namespace std::chrono_literals;
using S = LatencySnapshot;

TEST(LatencyHistogram, BucketEdges) {
  EXPECT_EQ(S::bucket_of(Nanos{-5}), 0u);
  EXPECT_EQ(S::bucket_of(Nanos{999}), 0u);
  EXPECT_EQ(S::bucket_of(1us), 1u);
  EXPECT_EQ(S::bucket_of(999us), 999u);
  EXPECT_EQ(S::bucket_of(1ms), 1000u);
  EXPECT_EQ(S::bucket_of(1009us), 1000u);
  EXPECT_EQ(S::bucket_of(1010us), 1001u);
  EXPECT_EQ(S::bucket_of(9999us), 1899u);
  EXPECT_EQ(S::bucket_of(10ms), 1900u);
  EXPECT_EQ(S::bucket_of(99'999us), 2799u);
  EXPECT_EQ(S::bucket_of(100ms), S::kOverflow);
  EXPECT_EQ(S::bucket_of(5s), S::kOverflow);
  for (std::size_t b = 0; b < S::kBuckets; ++b) {
    ASSERT_EQ(S::bucket_of(S::bucket_floor(b)), b) << b;
    if (b + 1 < S::kBuckets) {
      ASSERT_EQ(S::bucket_of(S::bucket_floor(b + 1) - Nanos{1}), b) << b;
    }
  }
}

TEST(LatencyHistogram, PercentilesMinMaxMean) {
  LatencyHistogram h;
  EXPECT_EQ(h.snapshot().count(), 0u);
  EXPECT_EQ(h.snapshot().percentile(0.5), Nanos{0});
  // 1..100 µs, one each (plus 400 ns so truncation shows).
  for (int us = 1; us <= 100; ++us) h.record(std::chrono::microseconds{us} + Nanos{400});
  const S s = h.snapshot();
  EXPECT_EQ(s.count(), 100u);
  EXPECT_EQ(s.min(), 1us + Nanos{400});
  EXPECT_EQ(s.max(), 100us + Nanos{400});
  EXPECT_EQ(s.percentile(0.50), 50us);
  EXPECT_EQ(s.percentile(0.99), 99us);
  EXPECT_EQ(s.percentile(1.0), 100us);
  EXPECT_EQ(s.percentile(0.0), 1us);
  EXPECT_EQ(s.mean(), Nanos{50'900});
  EXPECT_EQ(s.overflow(), 0u);
}

TEST(LatencyHistogram, CoarseRangesAndOverflow) {
  LatencyHistogram h;
  for (int i = 0; i < 97; ++i) h.record(10us);
  h.record(2345us);   // 10 µs buckets: floor 2340 µs
  h.record(45678us);  // 100 µs buckets: floor 45600 µs
  h.record(250ms);    // overflow: reported as the exact maximum
  const S s = h.snapshot();
  EXPECT_EQ(s.count(), 100u);
  EXPECT_EQ(s.overflow(), 1u);
  EXPECT_EQ(s.percentile(0.97), 10us);
  EXPECT_EQ(s.percentile(0.98), 2340us);
  EXPECT_EQ(s.percentile(0.99), 45600us);
  EXPECT_EQ(s.percentile(1.0), 250ms);
  EXPECT_EQ(s.max(), 250ms);
}

TEST(LatencyHistogram, AddMergeReset) {
  S a;
  a.add(5us, 10);
  a.add(7us, 10);
  S b;
  b.add(3us, 5);
  b.add(Nanos{-1}, 0);  // nothing
  a.merge(b);
  EXPECT_EQ(a.count(), 25u);
  EXPECT_EQ(a.min(), 3us);
  EXPECT_EQ(a.max(), 7us);
  EXPECT_EQ(a.percentile(0.2), 3us);
  EXPECT_EQ(a.percentile(0.5), 5us);
  S empty;
  a.merge(empty);
  EXPECT_EQ(a.count(), 25u);
  empty.merge(b);
  EXPECT_EQ(empty.min(), 3us);

  LatencyHistogram h;
  h.record(3us);
  h.reset();
  EXPECT_EQ(h.snapshot().count(), 0u);
  h.record(8us);
  EXPECT_EQ(h.snapshot().min(), 8us);
  EXPECT_EQ(h.snapshot().max(), 8us);
}

// A reader taking snapshots while the writer records: counts never go
// back, each snapshot is self-consistent (percentiles within [min, max]),
// and the final snapshot has everything.
TEST(LatencyHistogram, SnapshotsWhileRecording) {
  constexpr std::uint64_t kSamples = 2'000'000;
  LatencyHistogram h;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 0; i < kSamples; ++i) {
      h.record(Nanos{static_cast<std::int64_t>((i * 7919) % 3'000'000)});
    }
    done.store(true, std::memory_order_release);
  });
  std::uint64_t last_count = 0;
  int bad = 0;
  int snapshots = 0;
  while (!done.load(std::memory_order_acquire) || snapshots == 0) {
    const S s = h.snapshot();
    ++snapshots;
    if (s.count() < last_count) ++bad;
    last_count = s.count();
    if (s.count() > 0) {
      if (s.percentile(1.0) > s.max() || s.percentile(0.5) < S::bucket_floor(S::bucket_of(s.min())))
        ++bad;
    }
  }
  writer.join();
  EXPECT_EQ(bad, 0);
  const S s = h.snapshot();
  EXPECT_EQ(s.count(), kSamples);
  EXPECT_EQ(s.min(), Nanos{0});
  EXPECT_GT(snapshots, 0);
}

}  // namespace
}  // namespace smc::edge::rt
