#include "smc/edge/signals.hpp"

#include <cstring>

namespace smc::edge {

const char* signal_name(Signal s) noexcept {
  switch (s) {
    case Signal::kOperatorRequests:
      return "operator_requests";
    case Signal::kChatterSignalled:
      return "chatter_signalled";
    case Signal::kForcePeak:
      return "force_peak";
    case Signal::kContact:
      return "contact";
    case Signal::kChatterDetected:
      return "chatter_detected";
    case Signal::kSuppression:
      return "suppression";
    case Signal::kProgramRewritten:
      return "program_rewritten";
    case Signal::kGainEstimate:
      return "gain_estimate";
    case Signal::kControllerFeed:
      return "controller_feed";
    case Signal::kFeedCommand:
      return "feed_command";
    case Signal::kPowerLimit:
      return "power_limit";
    case Signal::kToolBreakage:
      return "tool_breakage";
    case Signal::kSpeedChange:
      return "speed_change";
  }
  return "";
}

namespace {

template <class T>
bool differs(const T& a, const T& b) noexcept {
  return std::memcmp(&a, &b, sizeof(T)) != 0;  // bitwise: NaN == NaN, -0 != +0
}

}  // namespace

SignalMask changed_signals(const Signals& x, const Signals& y) noexcept {
  SignalMask m = 0;
  auto mark = [&](bool changed, Signal s) {
    if (changed) m |= static_cast<SignalMask>(s);
  };
  mark(differs(x.feed_hold_requested, y.feed_hold_requested) ||
           differs(x.operator_chatter_event, y.operator_chatter_event),
       Signal::kOperatorRequests);
  mark(differs(x.chatter_signalled, y.chatter_signalled), Signal::kChatterSignalled);
  mark(differs(x.f_y_peak_n, y.f_y_peak_n) || differs(x.revolutions, y.revolutions) ||
           differs(x.f_y_updated, y.f_y_updated),
       Signal::kForcePeak);
  mark(differs(x.contact, y.contact), Signal::kContact);
  mark(differs(x.chatter_detected, y.chatter_detected) ||
           differs(x.chatter_ratio, y.chatter_ratio) ||
           differs(x.chatter_frequency_hz, y.chatter_frequency_hz) ||
           differs(x.chatter_vibration_ratio, y.chatter_vibration_ratio) ||
           differs(x.chatter_vibration_flip, y.chatter_vibration_flip),
       Signal::kChatterDetected);
  mark(differs(x.rewrite_requests, y.rewrite_requests) ||
           differs(x.suppression_hold, y.suppression_hold) ||
           differs(x.suppression_done, y.suppression_done),
       Signal::kSuppression);
  mark(differs(x.program_rewritten, y.program_rewritten), Signal::kProgramRewritten);
  mark(differs(x.gain_estimate, y.gain_estimate) || differs(x.gain_valid, y.gain_valid),
       Signal::kGainEstimate);
  mark(differs(x.controller_feed_per_tooth_mm, y.controller_feed_per_tooth_mm) ||
           differs(x.controller_valid, y.controller_valid),
       Signal::kControllerFeed);
  mark(differs(x.feedrate_cmd_mm_s, y.feedrate_cmd_mm_s) ||
           differs(x.feed_per_tooth_cmd_mm, y.feed_per_tooth_cmd_mm) ||
           differs(x.feed_limited, y.feed_limited),
       Signal::kFeedCommand);
  mark(differs(x.power_mean_w, y.power_mean_w) || differs(x.power_estimated, y.power_estimated) ||
           differs(x.force_reference_scale, y.force_reference_scale),
       Signal::kPowerLimit);
  mark(differs(x.tool_broken, y.tool_broken) || differs(x.breakage_window, y.breakage_window) ||
           differs(x.breakage_drop, y.breakage_drop),
       Signal::kToolBreakage);
  mark(differs(x.spindle_speed_cmd_rpm, y.spindle_speed_cmd_rpm) ||
           differs(x.speed_change_done, y.speed_change_done),
       Signal::kSpeedChange);
  return m;
}

}  // namespace smc::edge
