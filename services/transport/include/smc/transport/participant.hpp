#pragma once
// A domain participant, with the network profile pinned before it exists.

#include <cstdint>
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
  // DDS partition for every publisher and subscriber of this participant.
  // Tests use a unique one each, so concurrent tests never see each other.
  std::string partition;
};

class Participant {
 public:
  explicit Participant(ParticipantOptions options = {});
  Participant(Participant&&) noexcept = default;
  Participant& operator=(Participant&&) noexcept = default;

  EntityHandle handle() const noexcept { return entity_.handle(); }
  EntityHandle publisher() const noexcept { return publisher_.handle(); }
  EntityHandle subscriber() const noexcept { return subscriber_.handle(); }
  const ParticipantOptions& options() const noexcept { return options_; }

  // The compiled-in loopback profile (deploy/cyclonedds/loopback.xml).
  static const char* loopback_profile() noexcept;

 private:
  ParticipantOptions options_;
  Entity entity_;
  Entity publisher_;
  Entity subscriber_;
};

}  // namespace smc::transport
