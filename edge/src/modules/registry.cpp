#include "smc/edge/registry.hpp"

#include "smc/edge/modules.hpp"

namespace smc::edge {

namespace {

template <class M>
std::unique_ptr<Module> make() {
  return std::make_unique<M>();
}

}  // namespace

const ModuleRegistry& paper_modules() {
  // Data-flow order. Revolution modules: I measures F_Y, J thresholds it, M
  // scales F_ref from the revolution's power (while in contact), E
  // and H read the revolution's samples and F_Y, K and L read F_Y and H's
  // estimate. Fast modules: B reads the operator, D reads B, G reads E/D's
  // decision (through the supervisor). F serves G's request. N (tool
  // breakage) takes samples; O (speed change) reads E's frequency when the
  // supervisor starts it. A reads the
  // controllers and the supervisor's decision. C's activity is its action.
  static const ModuleRegistry kModules = {
      {ModuleId::I, &make<ForceSignalProcessor>},
      {ModuleId::J, &make<ContactMonitor>},
      {ModuleId::M, &make<SpindlePowerMonitor>},
      {ModuleId::E, &make<AutomaticChatterDetector>},
      {ModuleId::N, &make<ToolBreakageDetector>},
      {ModuleId::H, &make<ParameterEstimator>},
      {ModuleId::K, &make<AdaptiveForceController>},
      {ModuleId::L, &make<ModelBasedForceController>},
      {ModuleId::B, &make<OperatorInputMonitor>},
      {ModuleId::D, &make<OperatorChatterDetector>},
      {ModuleId::G, &make<ChatterSuppressionRoutine>},
      {ModuleId::F, &make<ChatterSuppressor>},
      {ModuleId::O, &make<SpindleSpeedChatterSuppressor>},
      {ModuleId::A, &make<FeedrateRoutine>},
      {ModuleId::C, &make<FeedHold>},
  };
  return kModules;
}

ModuleMask registry_mask(const ModuleRegistry& registry) noexcept {
  ModuleMask m = 0;
  for (const auto& e : registry) m = static_cast<ModuleMask>(m | bit(e.id));
  return m;
}

std::unique_ptr<Module> make_module(ModuleId id) {
  for (const auto& e : paper_modules()) {
    if (e.id == id) return e.make();
  }
  return nullptr;
}

}  // namespace smc::edge
