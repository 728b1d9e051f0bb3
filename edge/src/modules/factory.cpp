#include "smc/edge/modules.hpp"

namespace smc::edge {

std::unique_ptr<Module> make_module(ModuleId id) {
  switch (id) {
    case ModuleId::A:
      return std::make_unique<FeedrateRoutine>();
    case ModuleId::B:
      return std::make_unique<OperatorInputMonitor>();
    case ModuleId::C:
      return std::make_unique<FeedHold>();
    case ModuleId::D:
      return std::make_unique<OperatorChatterDetector>();
    case ModuleId::E:
      return std::make_unique<AutomaticChatterDetector>();
    case ModuleId::F:
      return std::make_unique<ChatterSuppressor>();
    case ModuleId::G:
      return std::make_unique<ChatterSuppressionRoutine>();
    case ModuleId::H:
      return std::make_unique<ParameterEstimator>();
    case ModuleId::I:
      return std::make_unique<ForceSignalProcessor>();
    case ModuleId::J:
      return std::make_unique<ContactMonitor>();
    case ModuleId::K:
      return std::make_unique<AdaptiveForceController>();
    case ModuleId::L:
      return std::make_unique<ModelBasedForceController>();
  }
  return nullptr;
}

}  // namespace smc::edge
