#pragma once
// A domain participant, with the network profile pinned before it exists.

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "smc/transport/entity.hpp"

namespace smc::transport {

struct ParticipantOptions {
  uint32_t domain_id = 0;
  // Cyclone DDS configuration: an XML string or "file://PATH". Empty means:
  // the CYCLONEDDS_URI environment variable if set, otherwise the project's
  // loopback profile compiled in (deploy/cyclonedds/loopback.xml). Cyclone is
  // never left to pick a network interface by itself.
  std::string config;
  // The cell's DDS partition. Tests use a unique one each, so concurrent
  // tests never see each other.
  std::string partition;
  // A machine's own participant (its edge): everything it publishes and
  // reads lives in that machine's partition (machine_partition()), which DDS
  // Security's permissions can grant to that machine's certificate alone.
  // Empty: a participant of the cell (cell service, dashboard, observers),
  // which publishes in the cell's partition, writes per-machine data into
  // each machine's partition (publisher_for) and reads the cell's partition
  // and every machine's.
  std::string machine;
};

// The partition of machine `machine` in cell partition `cell`:
// "<cell>/machine/<machine>" ("/machine/mill-1" in the default partition).
// Throws std::invalid_argument for a machine id that is not a letter or
// digit followed by letters, digits, '-', '_' or '.'.
std::string machine_partition(const std::string& cell, const std::string& machine);

// The machine whose partition `partition` is, in cell partition `cell`
// ("" when it is not a machine partition of that cell).
std::string machine_of_partition(const std::string& cell, const std::string& partition);

class Participant {
 public:
  explicit Participant(ParticipantOptions options = {});
  Participant(Participant&&) noexcept = default;
  Participant& operator=(Participant&&) noexcept = default;

  EntityHandle handle() const noexcept { return entity_.handle(); }
  EntityHandle publisher() const noexcept { return publisher_.handle(); }
  // A publisher in machine `machine`'s partition (created on first use; a
  // machine's participant has only its own, and throws
  // std::invalid_argument for another machine's). Thread-safe.
  EntityHandle publisher_for(const std::string& machine);
  EntityHandle subscriber() const noexcept { return subscriber_.handle(); }
  const ParticipantOptions& options() const noexcept { return options_; }
  // The participant lease it announces (Cyclone's Discovery/LeaseDuration):
  // how long its peers keep it after its last message.
  std::chrono::nanoseconds lease() const;

  // The compiled-in loopback profile (deploy/cyclonedds/loopback.xml).
  static const char* loopback_profile() noexcept;

 private:
  ParticipantOptions options_;
  Entity entity_;
  Entity publisher_;
  Entity subscriber_;
  struct Machines {
    std::mutex mu;
    std::map<std::string, Entity> publishers;
  };
  std::unique_ptr<Machines> machines_ = std::make_unique<Machines>();
};

}  // namespace smc::transport
