#include "smc/transport/qos.hpp"

#include "qos_apply.hpp"

namespace smc::transport {

QosProfile QosProfile::configuration() {
  QosProfile q;
  q.reliability = Reliability::kReliable;
  q.durability = Durability::kTransientLocal;
  q.history_depth = 1;
  return q;
}

QosProfile QosProfile::events() {
  QosProfile q;
  q.reliability = Reliability::kReliable;
  q.durability = Durability::kVolatile;
  q.history_depth = 0;
  return q;
}

QosProfile QosProfile::telemetry(int32_t depth) {
  QosProfile q;
  q.reliability = Reliability::kBestEffort;
  q.durability = Durability::kVolatile;
  q.history_depth = depth;
  return q;
}

namespace detail {

void apply(const QosProfile& p, dds_qos_t* qos) {
  dds_qset_reliability(qos,
                       p.reliability == Reliability::kReliable ? DDS_RELIABILITY_RELIABLE
                                                               : DDS_RELIABILITY_BEST_EFFORT,
                       p.max_blocking.count());
  dds_qset_durability(qos, p.durability == Durability::kTransientLocal
                               ? DDS_DURABILITY_TRANSIENT_LOCAL
                               : DDS_DURABILITY_VOLATILE);
  if (p.history_depth <= 0) {
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, p.history_depth);
  }
  if (p.liveliness_lease.count() != 0) {  // negative: let Cyclone reject it
    dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, p.liveliness_lease.count());
  }
}

}  // namespace detail
}  // namespace smc::transport
