#include "smc/wire/topics.hpp"

namespace smc::transport {

#define SMC_WIRE_TOPIC_DEF(T, NAME, QOS)              \
  const TypeSupport& TopicType<T>::get() {            \
    static const TypeSupport s{&T##_desc, NAME, QOS}; \
    return s;                                         \
  }

SMC_WIRE_TOPIC_DEF(smc_data_ForceSummary, "smc_force_summary", QosProfile::telemetry(8))
SMC_WIRE_TOPIC_DEF(smc_data_ForceBatch, "smc_force_batch", QosProfile::telemetry(4))
SMC_WIRE_TOPIC_DEF(smc_data_ChatterEvent, "smc_chatter_event", QosProfile::configuration())
SMC_WIRE_TOPIC_DEF(smc_data_SupervisorSituation, "smc_supervisor_situation",
                   QosProfile::configuration())
SMC_WIRE_TOPIC_DEF(smc_data_EdgeStatus, "smc_edge_status", QosProfile::configuration())
SMC_WIRE_TOPIC_DEF(smc_data_JobProgress, "smc_job_progress", QosProfile::configuration())
SMC_WIRE_TOPIC_DEF(smc_data_OperatorCommand, "smc_operator_command", QosProfile::events())
SMC_WIRE_TOPIC_DEF(smc_data_Envelope, "smc_config", QosProfile::configuration())
#undef SMC_WIRE_TOPIC_DEF

}  // namespace smc::transport
