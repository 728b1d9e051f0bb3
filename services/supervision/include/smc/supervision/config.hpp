#pragma once
// Validation of a supervisor configuration (smc.config.SupervisorConfig):
// parameters, module set, part program within the machine's limits, and the
// operation supervisor's Grafcet (bound to the modules and receptivities,
// then verified). Cell and edge call the same function: the cell before it
// sends a configuration, the edge before it accepts one. Not real-time.

#include <cstddef>
#include <memory>
#include <string>

#include "smc/supervision/grafcet_binding.hpp"
#include "smc/supervision/modules.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc/supervision/program.hpp"

namespace smc::config {
class SupervisorConfig;
}

namespace smc::supervision {

// Everything the edge's core needs, checked.
struct ValidatedConfig {
  std::string config_id;
  int variant = 0;  // smc.config.SmcVariant
  Parameters params;
  FixedProgram program;
  ModuleMask modules = 0;  // modules in use
  std::string grafcet_name;
  std::string grafcet_text;
  // The Grafcet, parsed, bound and verified (shared: copies of a validated
  // configuration never parse or verify again).
  std::shared_ptr<const BoundGrafcet> grafcet;
};

// The longest configuration id: it travels in 63-character wire strings
// (smc_edge_status.config_id, the envelope's document id; the edge bridge
// checks this against the IDL at compile time).
inline constexpr std::size_t kMaxConfigIdLength = 63;

// The paper's modules, A–L, and every module the project has, A–M.
inline constexpr ModuleMask kPaperModules = (1u << kPaperModuleCount) - 1;
inline constexpr ModuleMask kKnownModules = (1u << kModuleCount) - 1;

// Reads and checks the whole configuration, collecting every problem.
// Throws ConfigError listing them (field paths under "supervisor_config.",
// Grafcet problems as "file:line:col"). `known`: the modules a
// configuration may name (an edge passes the modules it has). The Grafcet
// is verified only when everything else is right.
ValidatedConfig validate(const smc::config::SupervisorConfig& cfg,
                         ModuleMask known = kKnownModules);

}  // namespace smc::supervision
