#include "smc/edge/realtime.hpp"

namespace smc::edge {

RealTimeEdge::RealTimeEdge(EdgeCore& core, rt::RtOptions options, Clock& clock)
    : core_(core), loop_(options, clock) {}

RealTimeEdge::~RealTimeEdge() { stop(); }

void RealTimeEdge::start() { loop_.start(&RealTimeEdge::trampoline, this); }

void RealTimeEdge::stop() { loop_.stop(); }

bool RealTimeEdge::push_operator_inputs(const OperatorInputs& in) noexcept {
  return inputs_.try_push(in);
}

void RealTimeEdge::trampoline(void* self, const rt::TickInfo& info) noexcept {
  static_cast<RealTimeEdge*>(self)->tick(info);
}

void RealTimeEdge::tick(const rt::TickInfo& info) noexcept {
  OperatorInputs in;
  bool any = false;
  while (inputs_.try_pop(in)) any = true;
  if (any) core_.set_operator_inputs(in);
  if (!core_.done()) core_.tick(info.overrun);
}

}  // namespace smc::edge
