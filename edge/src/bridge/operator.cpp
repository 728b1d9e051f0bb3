#include <spdlog/spdlog.h>

#include "bridge.hpp"
#include "smc/wire/names.hpp"

namespace smc::edge {

using smc::wire::get_string;

void EdgeService::Impl::take_commands() {
  bool changed = false;
  std::vector<std::string> log;  // logged after the loop has the inputs
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
      default:
        // A newer or corrupt sender: refused by name, nothing changes.
        spdlog::error(
            "{}: operator command {} from '{}' refused: action {} is not one of "
            "0 (feed hold on), 1 (feed hold off), 2 (chatter signal)",
            opt.machine_id, c.command_id, who, c.action);
        message = "operator command " + std::to_string(c.command_id) + " from '" + who +
                  "' refused: unknown action " + std::to_string(c.action);
        publish_status();
        return;
    }
    log.push_back(std::string(smc::wire::operator_action_name(c.action)) + " from '" + who +
                  "' (id " + std::to_string(c.command_id) + ")");
    changed = true;
  });
  if (changed && job) job->rt->push_operator_inputs(operator_inputs);
  for (const auto& l : log) spdlog::info("{}: operator command {}", opt.machine_id, l);
}

}  // namespace smc::edge
