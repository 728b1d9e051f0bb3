#include "smc/transport/participant.hpp"

#include <cstdlib>
#include <mutex>
#include <set>
#include <stdexcept>

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

std::string machine_partition(const std::string& cell, const std::string& machine) {
  bool ok = !machine.empty();
  for (size_t i = 0; ok && i < machine.size(); ++i) {
    const char c = machine[i];
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    ok = alnum || (i > 0 && (c == '-' || c == '_' || c == '.'));
  }
  if (!ok) {
    throw std::invalid_argument("machine id '" + machine +
                                "': use a letter or digit followed by letters, digits, '-', '_' "
                                "or '.' (it names the machine's DDS partition)");
  }
  return cell + "/machine/" + machine;
}

std::string machine_of_partition(const std::string& cell, const std::string& partition) {
  const std::string prefix = cell + "/machine/";
  if (partition.size() <= prefix.size() || partition.compare(0, prefix.size(), prefix) != 0) {
    return {};
  }
  std::string machine = partition.substr(prefix.size());
  // A pattern is nobody's partition.
  if (machine.find_first_of("*?[]/\\") != std::string::npos) return {};
  return machine;
}

Participant::Participant(ParticipantOptions options) : options_(std::move(options)) {
  ensure_domain(options_.domain_id, options_.config);
  entity_ = Entity(detail::check(dds_create_participant(options_.domain_id, nullptr, nullptr),
                                 "dds_create_participant",
                                 "domain " + std::to_string(options_.domain_id)));
  const std::string& cell = options_.partition;
  detail::Qos pub, sub;
  if (!options_.machine.empty()) {
    const std::string own = machine_partition(cell, options_.machine);
    dds_qset_partition1(pub.get(), own.c_str());
    dds_qset_partition1(sub.get(), own.c_str());
  } else {
    // The cell's partition, and every machine's of this cell.
    const std::string any = cell + "/machine/*";
    const char* names[] = {cell.c_str(), any.c_str()};
    if (!cell.empty()) dds_qset_partition1(pub.get(), cell.c_str());
    dds_qset_partition(sub.get(), 2, names);
  }
  const std::string what = options_.machine.empty() ? cell : options_.machine;
  publisher_ = Entity(detail::check(dds_create_publisher(entity_.handle(), pub.get(), nullptr),
                                    "dds_create_publisher", what));
  subscriber_ = Entity(detail::check(dds_create_subscriber(entity_.handle(), sub.get(), nullptr),
                                     "dds_create_subscriber", what));
}

std::chrono::nanoseconds Participant::lease() const {
  detail::Qos q;
  detail::check(dds_get_qos(entity_.handle(), q.get()), "dds_get_qos", "participant");
  dds_liveliness_kind_t kind{};
  dds_duration_t lease = DDS_INFINITY;
  if (!dds_qget_liveliness(q.get(), &kind, &lease)) lease = DDS_SECS(10);  // Cyclone's default
  return std::chrono::nanoseconds(lease);
}

EntityHandle Participant::publisher_for(const std::string& machine) {
  if (!options_.machine.empty()) {
    if (machine == options_.machine) return publisher_.handle();
    throw std::invalid_argument("the participant of machine '" + options_.machine +
                                "' cannot publish for machine '" + machine + "'");
  }
  std::lock_guard lock(machines_->mu);
  auto it = machines_->publishers.find(machine);
  if (it != machines_->publishers.end()) return it->second.handle();
  const std::string partition = machine_partition(options_.partition, machine);
  detail::Qos q;
  dds_qset_partition1(q.get(), partition.c_str());
  Entity p(detail::check(dds_create_publisher(entity_.handle(), q.get(), nullptr),
                         "dds_create_publisher", partition));
  const EntityHandle h = p.handle();
  machines_->publishers.emplace(machine, std::move(p));
  return h;
}

}  // namespace smc::transport
