#include "smc/edge/rt/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace smc::edge::rt {
namespace {

constexpr std::int64_t kMediumStartUs = 1'000;
constexpr std::int64_t kCoarseStartUs = 10'000;
constexpr std::int64_t kOverflowUs = 100'000;

}  // namespace

std::size_t LatencySnapshot::bucket_of(Nanos lateness) noexcept {
  const std::int64_t us = lateness.count() > 0 ? lateness.count() / 1'000 : 0;
  if (us < kMediumStartUs) return static_cast<std::size_t>(us);
  if (us < kCoarseStartUs) {
    return kFineBuckets + static_cast<std::size_t>((us - kMediumStartUs) / 10);
  }
  if (us < kOverflowUs) {
    return kFineBuckets + kMediumBuckets + static_cast<std::size_t>((us - kCoarseStartUs) / 100);
  }
  return kOverflow;
}

Nanos LatencySnapshot::bucket_floor(std::size_t bucket) noexcept {
  std::int64_t us = kOverflowUs;
  if (bucket < kFineBuckets) {
    us = static_cast<std::int64_t>(bucket);
  } else if (bucket < kFineBuckets + kMediumBuckets) {
    us = kMediumStartUs + static_cast<std::int64_t>(bucket - kFineBuckets) * 10;
  } else if (bucket < kOverflow) {
    us = kCoarseStartUs + static_cast<std::int64_t>(bucket - kFineBuckets - kMediumBuckets) * 100;
  }
  return Nanos{us * 1'000};
}

void LatencySnapshot::add(Nanos lateness, std::uint64_t n) noexcept {
  if (n == 0) return;
  const std::int64_t ns = std::max<std::int64_t>(lateness.count(), 0);
  counts_[bucket_of(lateness)] += n;
  min_ns_ = count_ == 0 ? ns : std::min(min_ns_, ns);
  max_ns_ = std::max(max_ns_, ns);
  sum_ns_ += ns * static_cast<std::int64_t>(n);
  count_ += n;
}

void LatencySnapshot::merge(const LatencySnapshot& other) noexcept {
  if (other.count_ == 0) return;
  for (std::size_t i = 0; i < kBuckets; ++i) counts_[i] += other.counts_[i];
  min_ns_ = count_ == 0 ? other.min_ns_ : std::min(min_ns_, other.min_ns_);
  max_ns_ = std::max(max_ns_, other.max_ns_);
  sum_ns_ += other.sum_ns_;
  count_ += other.count_;
}

Nanos LatencySnapshot::mean() const noexcept {
  if (count_ == 0) return Nanos{0};
  return Nanos{sum_ns_ / static_cast<std::int64_t>(count_)};
}

Nanos LatencySnapshot::percentile(double q) const noexcept {
  if (count_ == 0) return Nanos{0};
  q = std::clamp(q, 0.0, 1.0);
  auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  rank = std::clamp<std::uint64_t>(rank, 1, count_);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += counts_[i];
    if (seen >= rank) {
      if (i == kOverflow) return max();
      return std::min(bucket_floor(i), max());
    }
  }
  return max();
}

void LatencyHistogram::record(Nanos lateness) noexcept {
  const std::int64_t ns = std::max<std::int64_t>(lateness.count(), 0);
  // Single writer: plain load + store, no read-modify-write. Min, max and
  // sum first; the bucket's release store publishes them to a reader that
  // sees the bucket.
  if (ns < min_ns_.load(std::memory_order_relaxed)) min_ns_.store(ns, std::memory_order_relaxed);
  if (ns > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(ns, std::memory_order_relaxed);
  sum_ns_.store(sum_ns_.load(std::memory_order_relaxed) + ns, std::memory_order_relaxed);
  auto& bucket = counts_[LatencySnapshot::bucket_of(lateness)];
  bucket.store(bucket.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

LatencySnapshot LatencyHistogram::snapshot() const noexcept {
  LatencySnapshot s;
  for (std::size_t i = 0; i < LatencySnapshot::kBuckets; ++i) {
    s.counts_[i] = counts_[i].load(std::memory_order_acquire);
    s.count_ += s.counts_[i];
  }
  if (s.count_ > 0) {
    s.min_ns_ = min_ns_.load(std::memory_order_relaxed);
    s.max_ns_ = max_ns_.load(std::memory_order_relaxed);
    s.sum_ns_ = sum_ns_.load(std::memory_order_relaxed);
  }
  return s;
}

void LatencyHistogram::reset() noexcept {
  for (auto& c : counts_) c.store(0, std::memory_order_relaxed);
  min_ns_.store(std::numeric_limits<std::int64_t>::max(), std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
  sum_ns_.store(0, std::memory_order_release);
}

}  // namespace smc::edge::rt
