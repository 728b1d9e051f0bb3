#pragma once
// The names of the wire enums as the IDL spells them (EDGE_FEED_HOLD,
// JOB_DONE, OP_CHATTER_SIGNAL), for JSON, logs and test tools. Values off
// the enum (a newer or corrupt sender) get EDGE_UNKNOWN, JOB_UNKNOWN,
// OP_UNKNOWN.

namespace smc::wire {

const char* edge_state_name(int state) noexcept;
const char* job_phase_name(int phase) noexcept;
const char* operator_action_name(int action) noexcept;

}  // namespace smc::wire
