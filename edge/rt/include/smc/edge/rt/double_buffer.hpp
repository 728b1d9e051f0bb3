#pragma once
// Configuration swap at a cycle boundary (STYLE 12): a non-real-time writer
// publishes a new immutable object, built and allocated off the loop; the
// real-time side picks it up at the start of a cycle with one atomic
// exchange, and hands the object it stops using back through an SpscRing so
// that the writer deletes it. The real-time side never allocates, frees,
// locks or waits, and an object stays alive for as long as the real-time side
// may hold a pointer to it.
//
// Three places an object can be:
//   pending_  published by the writer, not yet seen by the real-time side
//             (a newer publish replaces it; the writer deletes the old one,
//             which the real-time side never saw);
//   current_  what the real-time side uses during the cycle;
//   retired_  stopped being current, waiting for the writer to delete it.
//
// Threads: exactly one writer thread (publish, reclaim) and one real-time
// thread (take_pending, current). Construction and destruction happen while
// neither runs.
//
// Real-time safe (no allocation, no free, no lock, no system call):
//   take_pending(), current(), swaps(), has_pending()
// Not real-time: constructor, destructor, publish(), reclaim().

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>

#include "smc/edge/rt/spsc_ring.hpp"

namespace smc::edge::rt {

template <class T, std::size_t RetireSlots = 8>
class DoubleBuffer {
 public:
  // Not real-time. `initial` is current from the first cycle; it must not be
  // null (the real-time side always has a configuration).
  explicit DoubleBuffer(std::unique_ptr<const T> initial) : current_(initial.release()) {
    if (current_ == nullptr) throw std::invalid_argument("DoubleBuffer: initial object is null");
  }
  DoubleBuffer(const DoubleBuffer&) = delete;
  DoubleBuffer& operator=(const DoubleBuffer&) = delete;

  // Not real-time; only when the real-time side no longer runs.
  ~DoubleBuffer() {
    reclaim();
    delete pending_.exchange(nullptr, std::memory_order_acquire);
    delete current_;
  }

  // Writer thread. Makes `next` the object the real-time side switches to at
  // its next take_pending(). An object published earlier and not yet taken
  // is deleted here (the real-time side never saw it). Also reclaims retired
  // objects. Returns false (and publishes nothing) when `next` is null.
  bool publish(std::unique_ptr<const T> next) {
    if (next == nullptr) return false;
    reclaim();
    const T* unseen = pending_.exchange(next.release(), std::memory_order_acq_rel);
    delete unseen;
    return true;
  }

  // Writer thread. Deletes the objects the real-time side has stopped using;
  // returns how many. Call it now and then (publish() calls it too).
  std::size_t reclaim() {
    std::size_t n = 0;
    const T* old = nullptr;
    while (retired_.try_pop(old)) {
      delete old;
      ++n;
    }
    return n;
  }

  // Real-time thread, at a cycle boundary. Switches to the pending object if
  // there is one and returns true. When the retire ring is full (the writer
  // has not reclaimed for RetireSlots swaps) the switch is deferred to a
  // later cycle instead of freeing anything here.
  bool take_pending() noexcept {
    if (pending_.load(std::memory_order_relaxed) == nullptr) return false;
    // Only this thread pushes to retired_, so a free slot seen now is still
    // free when we push below.
    if (retired_.size_approx() >= RetireSlots) return false;
    const T* next = pending_.exchange(nullptr, std::memory_order_acq_rel);
    if (next == nullptr) return false;
    const bool pushed = retired_.try_push(current_);
    static_cast<void>(pushed);  // cannot fail: checked for room above
    current_ = next;
    swaps_.store(swaps_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
    return true;
  }

  // Real-time thread. The object in use; stable until the next
  // take_pending() on this thread.
  const T& current() const noexcept { return *current_; }

  // Any thread: how many times the real-time side has switched objects.
  std::uint64_t swaps() const noexcept { return swaps_.load(std::memory_order_acquire); }
  // Any thread: a published object is waiting for the real-time side.
  bool has_pending() const noexcept { return pending_.load(std::memory_order_acquire) != nullptr; }

 private:
  std::atomic<const T*> pending_{nullptr};
  const T* current_;  // real-time thread only (after construction)
  std::atomic<std::uint64_t> swaps_{0};
  SpscRing<const T*, RetireSlots> retired_;
};

}  // namespace smc::edge::rt
