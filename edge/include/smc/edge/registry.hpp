#pragma once
// The modules an edge can run, in data-flow order: a module comes after
// every module whose outputs it reads in the same tick. The core builds its
// schedule from this order and each module's declarations (module.hpp).
// Adding a module is one line in registry.cpp; a test may pass its own
// registry (e.g. the paper's modules plus a test-only one).

#include <memory>
#include <vector>

#include "smc/edge/module.hpp"

namespace smc::edge {

struct ModuleEntry {
  ModuleId id;
  std::unique_ptr<Module> (*make)();
};
using ModuleRegistry = std::vector<ModuleEntry>;

// A–L of the paper's Table 1: I → J → E → H → K → L → B → D → G → F → A → C.
const ModuleRegistry& paper_modules();

// The mask of the modules a registry holds.
ModuleMask registry_mask(const ModuleRegistry& registry) noexcept;

}  // namespace smc::edge
