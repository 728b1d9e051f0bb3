// The edge core on the wall clock, in the real-time loop: it ticks, it does
// not allocate on the loop thread, operator inputs reach it through the
// ring, and a missed deadline holds the feed.

#include "smc/edge/realtime.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <optional>
#include <thread>

#include "alloc_counter.hpp"
#include "edge_test_config.hpp"
#include "smc/common/clock.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc_config.pb.h"

using namespace smc::edge;
using namespace std::chrono_literals;

namespace {

struct Fixture {
  smc::config::SupervisorConfig raw = test::shipped_config("smc1.textproto");
  EdgeConfig cfg = edge_config_from_proto(raw);
  SimulatedMill mill{raw.milling_model(), raw.simulation(), cfg.params.sample_period_s};
  EdgeCore core{cfg, mill};
  Fixture() { core.start(); }
};

// Wraps RealTimeEdge::tick to count allocations on the loop thread.
struct Guarded {
  RealTimeEdge* edge;
  std::optional<smc::test::ForbidAllocations> guard;
  std::atomic<uint64_t> violations{0};
  std::atomic<uint64_t> ticks{0};
  std::atomic<bool> stop{false};
  std::atomic<bool> released{false};
  static void tick(void* self, const smc::edge::rt::TickInfo& info) noexcept {
    auto* g = static_cast<Guarded*>(self);
    if (g->released) return;
    if (!g->guard) g->guard.emplace();
    g->edge->tick(info);
    g->violations = g->guard->violations();
    ++g->ticks;
    if (g->stop) {  // the guard ends on the thread that made it
      g->guard.reset();
      g->released = true;
    }
  }
};

}  // namespace

TEST(RealTimeEdge, TicksOnTheWallClockWithoutAllocating) {
  Fixture f;
  smc::RealClock clock;
  smc::edge::rt::RtOptions opts;
  opts.period = std::chrono::nanoseconds(static_cast<int64_t>(f.cfg.params.sample_period_s * 1e9));
  RealTimeEdge edge(f.core, opts, clock);
  Guarded g{&edge};
  smc::edge::rt::RtLoop loop(opts, clock);
  loop.start(&Guarded::tick, &g);
  // Hold the feed from the operator side while the loop runs.
  OperatorInputs op;
  op.feed_hold = true;
  while (g.ticks < 200) std::this_thread::sleep_for(1ms);
  ASSERT_TRUE(edge.push_operator_inputs(op));
  while (g.ticks < 600) std::this_thread::sleep_for(1ms);
  g.stop = true;
  while (!g.released) std::this_thread::sleep_for(1ms);
  loop.stop();
  EXPECT_EQ(g.violations.load(), 0u) << "the loop thread allocated";
  EXPECT_GE(f.core.ticks(), 600u);
  // The hold reached the core: module C active, feed zero (unless an
  // overrun on this shared machine held it first, which holds it too).
  EXPECT_NE(f.core.signals().active & bit(ModuleId::C), 0);
  EXPECT_EQ(f.core.signals().feedrate_cmd_mm_s, 0);
}

TEST(RealTimeEdge, AMissedDeadlineHoldsTheFeed) {
  Fixture f;
  smc::VirtualClock clock;
  smc::edge::rt::RtOptions opts;
  RealTimeEdge edge(f.core, opts, clock);
  edge.loop().run_for_ticks(
      100,
      [](void* self, const smc::edge::rt::TickInfo& info) noexcept {
        static_cast<RealTimeEdge*>(self)->tick(info);
      },
      &edge);
  EXPECT_FALSE(f.core.fault_hold());
  edge.loop().force_overrun();
  edge.loop().run_for_ticks(
      10,
      [](void* self, const smc::edge::rt::TickInfo& info) noexcept {
        static_cast<RealTimeEdge*>(self)->tick(info);
      },
      &edge);
  EXPECT_TRUE(f.core.fault_hold());
  EXPECT_EQ(f.core.fault(), Fault::kOverrun);
  EXPECT_EQ(f.core.signals().feedrate_cmd_mm_s, 0);
}
