// Replacement global operator new / delete that count allocations per
// thread and per process; see alloc_counter.hpp.

#include "alloc_counter.hpp"

#include <unistd.h>

#include <cstdlib>
#include <new>

namespace smc::test {
namespace {

// Plain integers with constant initialisers: thread_local access needs no
// TLS initialisation function, so it cannot allocate or recurse.
struct ThreadCounters {
  std::uint64_t allocations;
  std::uint64_t deallocations;
  std::uint64_t bytes;
};
thread_local ThreadCounters t_counters{0, 0, 0};
thread_local ForbidAllocations* t_guard = nullptr;

std::atomic<std::uint64_t> g_allocations{0};
std::atomic<std::uint64_t> g_deallocations{0};
std::atomic<std::uint64_t> g_bytes{0};

void write_stderr(const char* s) noexcept {
  std::size_t n = 0;
  while (s[n] != '\0') ++n;
  const ssize_t written = ::write(STDERR_FILENO, s, n);
  static_cast<void>(written);
}

}  // namespace

// Touches the guards' private state from the allocation hooks.
struct AllocHooks {
  static void on_allocate(std::size_t bytes) noexcept {
    ++t_counters.allocations;
    t_counters.bytes += bytes;
    g_allocations.fetch_add(1, std::memory_order_relaxed);
    g_bytes.fetch_add(bytes, std::memory_order_relaxed);
    bool abort = false;
    for (ForbidAllocations* g = t_guard; g != nullptr; g = g->outer_) {
      g->violations_.fetch_add(1, std::memory_order_acq_rel);
      abort = abort || g->mode_ == ForbidAllocations::Mode::kAbort;
    }
    if (abort) {
      write_stderr("alloc_counter: heap allocation on a thread under ForbidAllocations\n");
      std::abort();
    }
  }
  static void on_free() noexcept {
    ++t_counters.deallocations;
    g_deallocations.fetch_add(1, std::memory_order_relaxed);
  }
  static void push(ForbidAllocations* g) noexcept {
    g->outer_ = t_guard;
    t_guard = g;
  }
  static void pop(ForbidAllocations* g) noexcept {
    if (t_guard != g) {
      write_stderr(
          "alloc_counter: ForbidAllocations destroyed out of order or on another thread\n");
      std::abort();
    }
    t_guard = g->outer_;
  }
};

AllocStats thread_alloc_stats() noexcept {
  return {t_counters.allocations, t_counters.deallocations, t_counters.bytes};
}

AllocStats process_alloc_stats() noexcept {
  return {g_allocations.load(std::memory_order_relaxed),
          g_deallocations.load(std::memory_order_relaxed), g_bytes.load(std::memory_order_relaxed)};
}

AllocationCounter::AllocationCounter() noexcept : start_(thread_alloc_stats()) {}
std::uint64_t AllocationCounter::allocations() const noexcept {
  return t_counters.allocations - start_.allocations;
}
std::uint64_t AllocationCounter::deallocations() const noexcept {
  return t_counters.deallocations - start_.deallocations;
}
std::uint64_t AllocationCounter::bytes() const noexcept { return t_counters.bytes - start_.bytes; }

ForbidAllocations::ForbidAllocations(Mode mode) noexcept : mode_(mode), outer_(nullptr) {
  AllocHooks::push(this);
}
ForbidAllocations::~ForbidAllocations() { AllocHooks::pop(this); }

}  // namespace smc::test

namespace {

using smc::test::AllocHooks;

void* allocate(std::size_t n, std::size_t align, bool nothrow) {
  if (n == 0) n = 1;
  for (;;) {
    void* p = nullptr;
    if (align <= alignof(std::max_align_t)) {
      p = std::malloc(n);
    } else if (::posix_memalign(&p, align, n) != 0) {
      p = nullptr;
    }
    if (p != nullptr) {
      AllocHooks::on_allocate(n);
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) {
      if (nothrow) return nullptr;
      throw std::bad_alloc();
    }
    handler();
  }
}

void* allocate_nothrow(std::size_t n, std::size_t align) noexcept {
  try {
    return allocate(n, align, true);
  } catch (...) {
    return nullptr;
  }
}

void release(void* p) noexcept {
  if (p == nullptr) return;
  AllocHooks::on_free();
  std::free(p);
}

constexpr std::size_t kDefault = alignof(std::max_align_t);
std::size_t to_size(std::align_val_t a) noexcept { return static_cast<std::size_t>(a); }

}  // namespace

void* operator new(std::size_t n) { return allocate(n, kDefault, false); }
void* operator new[](std::size_t n) { return allocate(n, kDefault, false); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return allocate_nothrow(n, kDefault);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return allocate_nothrow(n, kDefault);
}
void* operator new(std::size_t n, std::align_val_t a) { return allocate(n, to_size(a), false); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocate(n, to_size(a), false); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_nothrow(n, to_size(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_nothrow(n, to_size(a));
}

void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
