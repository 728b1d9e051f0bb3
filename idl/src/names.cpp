#include "smc/wire/names.hpp"

#include "smc_data.h"

namespace smc::wire {

const char* edge_state_name(int state) noexcept {
  switch (state) {
    case smc_data_EDGE_IDLE:
      return "EDGE_IDLE";
    case smc_data_EDGE_CONFIGURED:
      return "EDGE_CONFIGURED";
    case smc_data_EDGE_RUNNING:
      return "EDGE_RUNNING";
    case smc_data_EDGE_FEED_HOLD:
      return "EDGE_FEED_HOLD";
    case smc_data_EDGE_FAULT:
      return "EDGE_FAULT";
    default:
      return "EDGE_UNKNOWN";
  }
}

const char* job_phase_name(int phase) noexcept {
  switch (phase) {
    case smc_data_JOB_ASSIGNED:
      return "JOB_ASSIGNED";
    case smc_data_JOB_RUNNING:
      return "JOB_RUNNING";
    case smc_data_JOB_DONE:
      return "JOB_DONE";
    case smc_data_JOB_FAILED:
      return "JOB_FAILED";
    case smc_data_JOB_INTERRUPTED:
      return "JOB_INTERRUPTED";
    default:
      return "JOB_UNKNOWN";
  }
}

const char* operator_action_name(int action) noexcept {
  switch (action) {
    case smc_data_OP_FEED_HOLD_ON:
      return "OP_FEED_HOLD_ON";
    case smc_data_OP_FEED_HOLD_OFF:
      return "OP_FEED_HOLD_OFF";
    case smc_data_OP_CHATTER_SIGNAL:
      return "OP_CHATTER_SIGNAL";
    default:
      return "OP_UNKNOWN";
  }
}

}  // namespace smc::wire
