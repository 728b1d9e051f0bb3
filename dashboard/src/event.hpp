#pragma once
// One message of the push stream (Server-Sent Events), formatted once and
// shared by every client that wants it.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace smc::dashboard {

enum class EventKind : std::uint8_t {
  kSummary,    // ForceSummary: F_Y, F_ref, feed, pass of one revolution
  kBatch,      // ForceBatch: raw F_y / F_z of one revolution (only with ?raw=1)
  kSituation,  // SupervisorSituation: active steps, modules, inputs
  kStatus,     // EdgeStatus, and the edge's liveliness
  kChatter,    // ChatterEvent
  kProgress,   // JobProgress
  kJob,        // JobStatus document
  kConfig,     // SupervisorConfig document (brief) and its Grafcet
  kProgram,    // PartProgram document
  kCommand,    // an operator command this dashboard sent
  kMill,       // a mill seen for the first time
  kCatalog,    // CatalogView document: the cell's catalog and its choices
};

const char* to_string(EventKind kind) noexcept;

struct Event {
  EventKind kind = EventKind::kSummary;
  std::string mill;                          // empty when the event is about no single mill
  std::shared_ptr<const std::string> frame;  // "event: KIND\ndata: JSON\n\n"
};

// Formats an SSE frame: "event: <kind>\ndata: <json>\n\n" (json has no newline).
Event make_event(EventKind kind, std::string mill, std::string_view json);

// Where events go (the stream hub). publish() may be called from any thread
// and must not block.
class EventSink {
 public:
  virtual ~EventSink() = default;
  virtual void publish(Event event) = 0;
};

}  // namespace smc::dashboard
