#include <spdlog/spdlog.h>

#include "bridge.hpp"

namespace smc::edge {

using smc::wire::get_string;

void EdgeService::Impl::take_commands() {
  bool changed = false;
  command_reader.take([&](const smc_data_OperatorCommand& c, const tr::SampleInfo& info) {
    if (!info.valid_data || get_string(c.machine_id) != opt.machine_id) return;
    const std::string who = get_string(c.operator_name);
    switch (c.action) {
      case smc_data_OP_FEED_HOLD_ON:
        operator_inputs.feed_hold = true;
        break;
      case smc_data_OP_FEED_HOLD_OFF:
        operator_inputs.feed_hold = false;
        ++operator_inputs.releases;
        break;
      case smc_data_OP_CHATTER_SIGNAL:
        ++operator_inputs.chatter_signals;
        break;
    }
    spdlog::info("{}: operator command {} from '{}' (id {})", opt.machine_id,
                 c.action == smc_data_OP_FEED_HOLD_ON    ? "feed hold on"
                 : c.action == smc_data_OP_FEED_HOLD_OFF ? "feed hold off"
                                                         : "chatter signal",
                 who, c.command_id);
    changed = true;
  });
  if (changed && job) job->rt->push_operator_inputs(operator_inputs);
}

}  // namespace smc::edge
