// Modules A (feedrate routine), B (operator input monitor), C (feed hold),
// D (operator chatter detector), F (chatter suppressor) and G (chatter
// suppression routine).

#include <algorithm>
#include <cmath>

#include "smc/edge/modules.hpp"

namespace smc::edge {

void FeedrateRoutine::configure(const EdgeParameters& p) { p_ = p; }

Status FeedrateRoutine::update(Signals& s) noexcept {
  // G holds the feed from the tick it becomes active (before its first
  // fast period has set suppression_hold) until it reports completion.
  const bool suppressing = (s.active & bit(ModuleId::G)) != 0 && !s.suppression_done;
  // O holds it while the spindle changes speed, likewise.
  const bool changing_speed = (s.active & bit(ModuleId::O)) != 0 && !s.speed_change_done;
  const bool hold = (s.active & bit(ModuleId::C)) != 0 || s.suppression_hold || suppressing ||
                    changing_speed || !s.in_pass;
  const bool control =
      (s.active & (bit(ModuleId::K) | bit(ModuleId::L))) != 0 && s.controller_valid;
  double feedrate = s.programmed_feedrate_mm_s;
  if (control) feedrate = p_.feedrate_for(s.controller_feed_per_tooth_mm, s.spindle_rpm);
  if (hold) feedrate = 0;
  const double limit =
      std::min(p_.max_feedrate_mm_s, p_.feedrate_for(p_.max_feed_per_tooth_mm, s.spindle_rpm));
  s.feed_limited = feedrate > limit || !(feedrate >= 0);
  if (!(feedrate >= 0)) feedrate = 0;  // NaN or negative: stop
  feedrate = std::min(feedrate, limit);
  s.feedrate_cmd_mm_s = feedrate;
  s.feed_per_tooth_cmd_mm = p_.feed_per_tooth_for(feedrate, s.spindle_rpm);
  return Status::kOk;
}

Status OperatorInputMonitor::update(Signals& s) noexcept {
  s.feed_hold_requested = s.operator_inputs.feed_hold;
  const uint32_t n = s.operator_inputs.chatter_signals;
  // Signals that arrived before the monitor first ran are not news.
  s.operator_chatter_event = primed_ && n != seen_chatter_signals_;
  seen_chatter_signals_ = n;
  primed_ = true;
  return Status::kOk;
}

Status OperatorChatterDetector::update(Signals& s) noexcept {
  s.chatter_signalled = s.operator_chatter_event;
  return Status::kOk;
}

Status ChatterSuppressor::update(Signals& s) noexcept {
  if (s.rewrite_requests == served_) return Status::kOk;
  served_ = s.rewrite_requests;
  if (program_ == nullptr) return fail("no program to rewrite");
  if (!add_one_pass(program_->program, program_->current_pass)) {
    return fail("the program has no room for another pass (16 at most)");
  }
  s.program_rewritten = true;
  return Status::kOk;
}

Status ChatterSuppressionRoutine::update(Signals& s) noexcept {
  if (!started_) {
    started_ = true;
    elapsed_fast_ = 0;
    ++s.rewrite_requests;
    s.suppression_hold = true;
    s.suppression_done = false;
    return Status::kOk;
  }
  ++elapsed_fast_;
  const double held_s = elapsed_fast_ * p_.fast_period_s;
  if (held_s + 1e-12 >= p_.suppression_hold_s) {
    s.suppression_hold = false;
    s.suppression_done = true;
  }
  return Status::kOk;
}

}  // namespace smc::edge
