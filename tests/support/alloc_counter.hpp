#pragma once
// Heap-allocation counting for tests of real-time code.
//
// Linking tests/support/alloc_counter.cpp into a test binary replaces the
// global operator new / delete (every form: plain, array, nothrow, aligned,
// sized) with versions that call malloc / free and count, per thread and in
// total. Nothing else changes. Add it to the test's SOURCES:
//
//   smc_add_gtest(my_test SOURCES my_test.cpp
//                 ${CMAKE_SOURCE_DIR}/tests/support/alloc_counter.cpp LIBS ...)
//
// Typical use on the thread under test (for a loop thread, keep the guard
// in a std::optional in the tick context: emplace it on the first tick,
// reset it on the last; neither allocates):
//
//   smc::test::ForbidAllocations guard;   // this thread, from here on
//   run_the_real_time_path();
//   EXPECT_EQ(guard.violations(), 0u);
//
// Only operator new is seen: direct malloc() calls (C libraries) are not.
// Everything here is safe to call from any thread and never allocates.

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace smc::test {

struct AllocStats {
  std::uint64_t allocations = 0;    // calls to any operator new that succeeded
  std::uint64_t deallocations = 0;  // calls to any operator delete with a non-null pointer
  std::uint64_t bytes = 0;          // bytes asked for by those allocations
};

// Since the calling thread started.
AllocStats thread_alloc_stats() noexcept;
// All threads, since the process started.
AllocStats process_alloc_stats() noexcept;

// Counts what the calling thread allocates while the object lives. Read it
// on the thread that made it.
class AllocationCounter {
 public:
  AllocationCounter() noexcept;
  std::uint64_t allocations() const noexcept;
  std::uint64_t deallocations() const noexcept;
  std::uint64_t bytes() const noexcept;

 private:
  AllocStats start_;
};

// While alive, every operator new on the calling thread is a violation:
// counted (and, with Mode::kAbort, reported on stderr and the process
// aborted, so that a debugger or core dump shows the call stack). Guards
// nest; an allocation counts in every live guard of its thread. Make and
// destroy it on the same thread; violations() may be read from any thread.
class ForbidAllocations {
 public:
  enum class Mode { kCount, kAbort };
  explicit ForbidAllocations(Mode mode = Mode::kCount) noexcept;
  ~ForbidAllocations();
  ForbidAllocations(const ForbidAllocations&) = delete;
  ForbidAllocations& operator=(const ForbidAllocations&) = delete;

  // Allocations made on the guarded thread while this guard lived.
  std::uint64_t violations() const noexcept { return violations_.load(std::memory_order_acquire); }

 private:
  friend struct AllocHooks;
  std::atomic<std::uint64_t> violations_{0};
  Mode mode_;
  ForbidAllocations* outer_;
};

}  // namespace smc::test
