#include "smc/transport/topic.hpp"

#include "qos_apply.hpp"
#include "smc/transport/participant.hpp"

namespace smc::transport {

TopicBase::TopicBase(Participant& participant, const TypeSupport& type, const std::string& name,
                     const QosProfile& qos)
    : participant_(&participant), name_(name), qos_(qos) {
  detail::Qos q;
  detail::apply(qos, q.get());
  entity_ = Entity(detail::check(
      dds_create_topic(participant.handle(), type.descriptor, name.c_str(), q.get(), nullptr),
      "dds_create_topic", name));
}

}  // namespace smc::transport
