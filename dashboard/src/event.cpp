#include "event.hpp"

namespace smc::dashboard {

const char* to_string(EventKind kind) noexcept {
  switch (kind) {
    case EventKind::kSummary:
      return "summary";
    case EventKind::kBatch:
      return "batch";
    case EventKind::kSituation:
      return "situation";
    case EventKind::kStatus:
      return "status";
    case EventKind::kChatter:
      return "chatter";
    case EventKind::kProgress:
      return "progress";
    case EventKind::kJob:
      return "job";
    case EventKind::kConfig:
      return "config";
    case EventKind::kProgram:
      return "program";
    case EventKind::kCommand:
      return "command";
    case EventKind::kMill:
      return "mill";
    case EventKind::kCatalog:
      return "catalog";
  }
  return "unknown";
}

Event make_event(EventKind kind, std::string mill, std::string_view json) {
  std::string frame;
  frame.reserve(json.size() + 32);
  frame += "event: ";
  frame += to_string(kind);
  frame += "\ndata: ";
  frame += json;
  frame += "\n\n";
  return Event{kind, std::move(mill), std::make_shared<const std::string>(std::move(frame))};
}

}  // namespace smc::dashboard
