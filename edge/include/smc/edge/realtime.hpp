#pragma once
// The edge core on the wall clock: one real-time thread (edge/rt's RtLoop)
// ticks the core every sample period with absolute-time sleeps; operator
// inputs arrive through a lock-free ring; a missed deadline reaches the core
// as an overrun, which holds the feed. Telemetry and events leave through
// the core's own rings, drained by the caller's comms thread.

#include "smc/edge/core.hpp"
#include "smc/edge/rt/rt_loop.hpp"
#include "smc/edge/rt/spsc_ring.hpp"

namespace smc::edge {

class RealTimeEdge {
 public:
  // `core` must be start()ed and outlive this object.
  RealTimeEdge(EdgeCore& core, rt::RtOptions options, Clock& clock);
  ~RealTimeEdge();
  RealTimeEdge(const RealTimeEdge&) = delete;
  RealTimeEdge& operator=(const RealTimeEdge&) = delete;

  // Starts the loop thread (real-time set-up first; see setup_report()).
  void start();
  void stop();

  // Any one non-real-time thread: the latest operator inputs. Never blocks;
  // false if the ring is full (the loop takes them every tick).
  bool push_operator_inputs(const OperatorInputs& in) noexcept;

  // Real-time: one tick (what the loop thread runs; public for tests that
  // wrap it).
  void tick(const rt::TickInfo& info) noexcept;

  rt::RtLoop& loop() noexcept { return loop_; }
  const rt::RtSetupReport& setup_report() const noexcept { return loop_.setup_report(); }

 private:
  static void trampoline(void* self, const rt::TickInfo& info) noexcept;
  EdgeCore& core_;
  rt::RtLoop loop_;
  rt::SpscRing<OperatorInputs, 16> inputs_;
};

}  // namespace smc::edge
