#pragma once
// QoS by intent. Each topic's intent is written beside its type in
// idl/smc_data.idl; code asks for an intent, never for raw QoS.

#include <chrono>
#include <cstdint>

namespace smc::transport {

enum class Reliability : uint8_t { kBestEffort, kReliable };
enum class Durability : uint8_t { kVolatile, kTransientLocal };

struct QosProfile {
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  int32_t history_depth = 1;  // 0 means keep-all
  // Automatic liveliness lease; zero means infinite (no liveliness checks).
  std::chrono::nanoseconds liveliness_lease{0};
  // How long a reliable writer may block when the reader's history is full.
  std::chrono::nanoseconds max_blocking{std::chrono::milliseconds(100)};

  // Configuration and durable records: reliable, transient-local, keep-last 1
  // per key, so a late-joining or restarted reader gets the current value.
  static QosProfile configuration();
  // Events: reliable, keep-all, volatile.
  static QosProfile events();
  // Telemetry: best-effort, keep-last `depth` per key.
  static QosProfile telemetry(int32_t depth = 8);

  QosProfile with_lease(std::chrono::nanoseconds lease) const {
    QosProfile q = *this;
    q.liveliness_lease = lease;
    return q;
  }
  QosProfile with_depth(int32_t depth) const {
    QosProfile q = *this;
    q.history_depth = depth;
    return q;
  }
};

}  // namespace smc::transport
