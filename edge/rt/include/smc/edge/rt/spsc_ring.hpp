#pragma once
// Fixed-size single-producer / single-consumer ring: how the real-time loop
// hands samples to the rest of the process and takes commands back without
// ever waiting. One thread pushes, one (other) thread pops; neither blocks.
//
// Real-time safe (no allocation, no lock, no system call, O(1)):
//   try_push()      producer thread only
//   try_pop()       consumer thread only
//   size_approx(), dropped(), capacity()   any thread
// Not real-time: the constructor (allocates the N slots once) and the
// destructor (frees them).
//
// Memory order: the producer writes the slot, then publishes it with a
// release store of head_; the consumer reads head_ with acquire before it
// reads the slot, and releases the slot back with a release store of tail_.
// Each side keeps a private copy of the other side's index so that it touches
// the shared cache line only when the ring looks full (producer) or empty
// (consumer).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>

namespace smc::edge::rt {

// Destructive-interference size, fixed so that the layout does not depend on
// compiler flags (GCC warns when std::hardware_destructive_interference_size
// is used in a header for that reason).
inline constexpr std::size_t kCacheLine = 64;

template <class T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscRing: N must be a power of two >= 2");
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing: T must be trivially copyable");
  static_assert(std::is_default_constructible_v<T>, "SpscRing: T must be default-constructible");

 public:
  // Not real-time: allocates and zero-initialises the N slots (which also
  // pre-faults their pages).
  SpscRing() : slots_(new T[N]()) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;
  ~SpscRing() = default;

  static constexpr std::size_t capacity() noexcept { return N; }

  // Producer only. Copies `item` into the ring; returns false, and counts a
  // drop, when the ring is full. Never waits.
  bool try_push(const T& item) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= N) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= N) {
        dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        return false;
      }
    }
    slots_[head & kMask] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer only. Moves the oldest item into `out`; returns false when the
  // ring is empty (then `out` is untouched). Never waits.
  bool try_pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & kMask];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Any thread: number of items in the ring at some instant during the call
  // (exact when called by the producer or the consumer while the other side
  // is idle), in [0, N].
  std::size_t size_approx() const noexcept {
    // tail first: head only grows and never passes tail + N at any instant,
    // so a later head is >= this tail.
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t n = head - tail;
    return n > N ? N : n;
  }

  // Any thread: pushes refused because the ring was full, since construction.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kMask = N - 1;

  // Producer's cache line: what it writes, and its copy of the consumer index.
  alignas(kCacheLine) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;
  std::atomic<std::uint64_t> dropped_{0};
  // Consumer's cache line.
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;
  // Read-only after construction: its own line, so that the pointer does not
  // share a line with either index.
  alignas(kCacheLine) const std::unique_ptr<T[]> slots_;
};

}  // namespace smc::edge::rt
