#include "command.hpp"

#include "json.hpp"

namespace smc::dashboard {

const char* to_string(CommandAction action) noexcept {
  switch (action) {
    case CommandAction::kFeedHoldOn:
      return "feed_hold_on";
    case CommandAction::kFeedHoldOff:
      return "feed_hold_off";
    case CommandAction::kChatterSignal:
      return "chatter_signal";
  }
  return "unknown";
}

std::optional<CommandAction> parse_action(std::string_view name) noexcept {
  if (name == "feed_hold_on") return CommandAction::kFeedHoldOn;
  if (name == "feed_hold_off") return CommandAction::kFeedHoldOff;
  if (name == "chatter_signal") return CommandAction::kChatterSignal;
  return std::nullopt;
}

std::string to_json(const CommandRecord& record) {
  JsonWriter w;
  w.begin_object()
      .field("command_id", std::to_string(record.command_id))
      .field("machine_id", record.request.machine_id)
      .field("action", to_string(record.request.action))
      .field("operator", record.request.operator_name)
      .field("remote", record.request.remote)
      .field("issued_unix_ns", std::to_string(record.issued_unix_ns))
      .field("issued_unix_ms", static_cast<double>(record.issued_unix_ns) * 1e-6)
      .field("sent", record.sent);
  if (!record.sent) w.field("error", record.error);
  w.end_object();
  return w.take();
}

}  // namespace smc::dashboard
