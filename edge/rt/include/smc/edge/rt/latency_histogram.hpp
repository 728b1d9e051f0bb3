#pragma once
// Wake-up latency histogram of the real-time loop.
//
// Buckets (lateness truncated to whole microseconds, as cyclictest does):
//   [0, 1 ms)        1 µs wide   (1000 buckets)
//   [1 ms, 10 ms)   10 µs wide    (900 buckets)
//   [10 ms, 100 ms) 100 µs wide   (900 buckets)
//   >= 100 ms        one overflow bucket
// Negative lateness (the clock woke us early) counts as 0. Minimum, maximum
// and sum are kept exactly, in nanoseconds.
//
// LatencyHistogram has one writer, the loop thread; every field is an atomic
// that only that thread stores to, so record() is a handful of plain loads
// and stores, and any other thread may take a snapshot() at any time without
// tearing a value or blocking the writer. A snapshot taken while the writer
// runs may miss the samples recorded during the copy; it never contains a
// half-written count, and its maximum is never below a sample it counts.
//
// Real-time safe: LatencyHistogram::record() (writer thread only),
//                 LatencyHistogram::snapshot() (no allocation; copies ~22 KB).
// Not real-time:  nothing here allocates, but LatencySnapshot's queries walk
//                 all buckets; use them off the loop.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "smc/common/clock.hpp"

namespace smc::edge::rt {

class LatencySnapshot {
 public:
  static constexpr std::size_t kFineBuckets = 1000;   // 1 µs, to 1 ms
  static constexpr std::size_t kMediumBuckets = 900;  // 10 µs, to 10 ms
  static constexpr std::size_t kCoarseBuckets = 900;  // 100 µs, to 100 ms
  static constexpr std::size_t kOverflow = kFineBuckets + kMediumBuckets + kCoarseBuckets;
  static constexpr std::size_t kBuckets = kOverflow + 1;

  // Bucket that holds `lateness`, and the lowest lateness a bucket holds.
  static std::size_t bucket_of(Nanos lateness) noexcept;
  static Nanos bucket_floor(std::size_t bucket) noexcept;

  // Adds `n` samples of `lateness` (used to load external histograms, such
  // as cyclictest's, so that both are summarised the same way).
  void add(Nanos lateness, std::uint64_t n = 1) noexcept;
  void merge(const LatencySnapshot& other) noexcept;

  std::uint64_t count() const noexcept { return count_; }
  std::uint64_t overflow() const noexcept { return counts_[kOverflow]; }
  Nanos min() const noexcept { return count_ == 0 ? Nanos{0} : Nanos{min_ns_}; }
  Nanos max() const noexcept { return Nanos{max_ns_}; }
  Nanos mean() const noexcept;
  // Nearest-rank percentile, q in [0, 1]: the floor of the bucket holding
  // the ceil(q * count)-th smallest sample (so 1 µs resolution below 1 ms),
  // never above max(). 0 when empty.
  Nanos percentile(double q) const noexcept;
  std::uint64_t bucket_count(std::size_t bucket) const noexcept {
    return bucket < kBuckets ? counts_[bucket] : 0;
  }

 private:
  friend class LatencyHistogram;
  std::array<std::uint64_t, kBuckets> counts_{};
  std::uint64_t count_ = 0;
  std::int64_t min_ns_ = 0;
  std::int64_t max_ns_ = 0;
  std::int64_t sum_ns_ = 0;
};

class LatencyHistogram {
 public:
  // Writer thread only. Real-time safe.
  void record(Nanos lateness) noexcept;
  // Any thread. Real-time safe (no allocation, no lock).
  LatencySnapshot snapshot() const noexcept;
  // Writer thread only, or while no writer runs.
  void reset() noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, LatencySnapshot::kBuckets> counts_{};
  std::atomic<std::int64_t> min_ns_{std::numeric_limits<std::int64_t>::max()};
  std::atomic<std::int64_t> max_ns_{0};
  std::atomic<std::int64_t> sum_ns_{0};
};

}  // namespace smc::edge::rt
