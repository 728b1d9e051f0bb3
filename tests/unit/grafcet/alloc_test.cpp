// The engine does not allocate after construction: evaluate() and reset()
// are counted against a replacement global operator new.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "grafcet_test_util.hpp"
#include "smc/grafcet/engine.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

// Replacing the global operators: delete frees what this new mallocs. GCC
// cannot see that pairing and would warn -Wmismatched-new-delete.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace smc::grafcet {
namespace {

TEST(GrafcetEngineAllocation, CounterSeesAllocations) {
  const long before = g_allocations.load();
  void* p = ::operator new(16);  // a call, not a new-expression: never elided
  ::operator delete(p);
  EXPECT_EQ(g_allocations.load() - before, 1);
}

TEST(GrafcetEngineAllocation, EvaluateAndResetNeverAllocate) {
  for (const char* file : {"smc1.grafcet", "smc1_guarded.grafcet", "smc2.grafcet",
                           "smc2_plus.grafcet", "broken/smc2_printed.grafcet"}) {
    const Grafcet g = testing::load_ok(file);
    Engine engine(g);
    const long before = g_allocations.load();
    Mask in = 0;
    std::uint64_t x = 88172645463325252ull;
    std::size_t unstable = 0;
    for (int i = 0; i < 200000; ++i) {
      x ^= x << 13;
      x ^= x >> 7;
      x ^= x << 17;
      in ^= x & (x >> 5) & 0x1Fu;
      const Evaluation& r = engine.evaluate(in);
      unstable += r.unstable ? 1u : 0u;
      if (i % 5000 == 4999) engine.reset();
      (void)engine.last();
      (void)engine.input_index("d");
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << file;
    if (std::string(file).find("printed") != std::string::npos) {
      EXPECT_GT(unstable, 0u);  // the unstable path was exercised too
    }
  }
}

}  // namespace
}  // namespace smc::grafcet
