// The edge's acceptance of a configuration: the shared validation, then
// what only the edge knows — its module registry and the modules' declared
// outputs.

#include <string>

#include "smc/edge/core.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

EdgeConfig edge_config_from_proto(const smc::config::SupervisorConfig& cfg,
                                  const ModuleRegistry& registry) {
  EdgeConfig c = supervision::validate(cfg, registry_mask(registry));
  common::Diagnostics problems;
  SignalMask owned = 0;
  ModuleId owner[32] = {};
  for (const ModuleEntry& e : registry) {
    if (!has(c.modules, e.id)) continue;
    const SignalMask writes = e.make()->writes();
    for (int b = 0; b < 32; ++b) {
      const SignalMask sig = SignalMask{1} << b;
      if ((writes & sig) == 0) continue;
      if ((owned & sig) != 0) {
        const std::string a(1, letter(owner[b])), m(1, letter(e.id));
        problems.add("supervisor_config.modules",
                     "modules " + a + " and " + m + " both write the signal " +
                         signal_name(static_cast<Signal>(sig)) + "; each signal has one owner",
                     "configure only one of " + a + " and " + m);
      }
      owned |= sig;
      owner[b] = e.id;
    }
  }
  if (!problems.ok()) throw ConfigError(std::move(problems));
  return c;
}

}  // namespace smc::edge
