#pragma once
// Operator commands as the REST API names them, and the record the dashboard
// keeps of each one it sent (logged, listed by /api/commands, streamed).

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace smc::dashboard {

enum class CommandAction : std::uint8_t { kFeedHoldOn, kFeedHoldOff, kChatterSignal };

// "feed_hold_on", "feed_hold_off", "chatter_signal".
const char* to_string(CommandAction action) noexcept;
std::optional<CommandAction> parse_action(std::string_view name) noexcept;

struct CommandRequest {
  std::string machine_id;
  CommandAction action = CommandAction::kFeedHoldOn;
  std::string operator_name;
  std::string remote;  // client address, for the log
};

struct CommandRecord {
  CommandRequest request;
  std::uint64_t command_id = 0;
  std::uint64_t issued_unix_ns = 0;
  bool sent = false;  // written to DDS
  std::string error;  // why not, when !sent
};

// JSON object of a record (what /api/commands lists and the stream sends).
std::string to_json(const CommandRecord& record);

// Accepts command requests from HTTP handlers (any thread) and completes
// them later, on another thread. Implemented by the DDS bridge.
class CommandSink {
 public:
  using Done = std::function<void(const CommandRecord&)>;
  virtual ~CommandSink() = default;
  virtual void submit(CommandRequest request, Done done) = 0;
};

}  // namespace smc::dashboard
