#include "smc/transport/participant.hpp"

#include <cstdlib>
#include <mutex>
#include <set>

#include "check.hpp"

namespace smc::transport {

extern const char* const kLoopbackProfileXml;  // generated from deploy/cyclonedds

const char* Participant::loopback_profile() noexcept { return kLoopbackProfileXml; }

namespace {

// A domain's configuration is fixed by the first participant in the process.
// Create the domain explicitly so that, unless the operator set
// CYCLONEDDS_URI, the loopback profile applies rather than Cyclone's default
// (which would pick a network interface by itself).
void ensure_domain(uint32_t domain_id, const std::string& config) {
  static std::mutex mu;
  static std::set<uint32_t> created;
  std::lock_guard lock(mu);
  if (created.count(domain_id)) return;
  std::string cfg = config;
  if (cfg.empty()) {
    const char* env = std::getenv("CYCLONEDDS_URI");
    if (env == nullptr || *env == '\0') cfg = kLoopbackProfileXml;
  }
  if (!cfg.empty()) {
    dds_entity_t d = dds_create_domain(domain_id, cfg.c_str());
    // PRECONDITION_NOT_MET: the domain exists already (created by Cyclone).
    if (d < 0 && d != DDS_RETCODE_PRECONDITION_NOT_MET) {
      detail::check(d, "dds_create_domain", "domain " + std::to_string(domain_id));
    }
  }
  created.insert(domain_id);
}

}  // namespace

Participant::Participant(ParticipantOptions options) : options_(std::move(options)) {
  ensure_domain(options_.domain_id, options_.config);
  entity_ = Entity(detail::check(dds_create_participant(options_.domain_id, nullptr, nullptr),
                                 "dds_create_participant",
                                 "domain " + std::to_string(options_.domain_id)));
  detail::Qos qos;
  if (!options_.partition.empty()) dds_qset_partition1(qos.get(), options_.partition.c_str());
  publisher_ = Entity(detail::check(dds_create_publisher(entity_.handle(), qos.get(), nullptr),
                                    "dds_create_publisher", options_.partition));
  subscriber_ = Entity(detail::check(dds_create_subscriber(entity_.handle(), qos.get(), nullptr),
                                     "dds_create_subscriber", options_.partition));
}

}  // namespace smc::transport
