#pragma once
#include "check.hpp"
#include "smc/transport/qos.hpp"

namespace smc::transport::detail {
void apply(const QosProfile& profile, dds_qos_t* qos);
}
