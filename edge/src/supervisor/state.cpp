#include "smc/edge/supervisor.hpp"

namespace smc::edge {

uint32_t receptivities(const Signals& s, bool fault_hold) noexcept {
  uint32_t in = 0;
  if (s.feed_hold_requested || fault_hold) in |= 1u << kInputA;
  if (s.contact) in |= 1u << kInputB;
  if (s.chatter_signalled) in |= 1u << kInputC;
  if (s.chatter_detected) in |= 1u << kInputD;
  if (s.suppression_done) in |= 1u << kInputE;
  if (s.tool_broken) in |= 1u << kInputF;
  if (s.speed_change_done) in |= 1u << kInputG;
  if (s.speed_changed_in_pass) in |= 1u << kInputH;
  return in;
}

}  // namespace smc::edge
