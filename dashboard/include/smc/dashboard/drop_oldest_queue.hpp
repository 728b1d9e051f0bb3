#pragma once
// The per-client queue of the dashboard's push stream: bounded, and when
// full it drops the oldest entry and counts it, so a client that stops
// reading costs a fixed amount of memory and never holds up the others.
// Not thread-safe: each stream client's queue is used on the server's I/O
// thread only.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>

namespace smc::dashboard {

template <class T>
class DropOldestQueue {
 public:
  explicit DropOldestQueue(std::size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  // Appends `v`; returns true when an older entry had to be dropped for it.
  bool push(T v) {
    bool dropped = false;
    if (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped_;
      dropped = true;
    }
    items_.push_back(std::move(v));
    return dropped;
  }
  T pop() {
    T v = std::move(items_.front());
    items_.pop_front();
    return v;
  }

  bool empty() const noexcept { return items_.empty(); }
  std::size_t size() const noexcept { return items_.size(); }
  std::size_t capacity() const noexcept { return capacity_; }
  // Entries dropped since construction.
  std::uint64_t dropped() const noexcept { return dropped_; }

 private:
  std::size_t capacity_;
  std::deque<T> items_;
  std::uint64_t dropped_ = 0;
};

}  // namespace smc::dashboard
