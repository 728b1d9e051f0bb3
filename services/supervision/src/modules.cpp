#include "smc/supervision/modules.hpp"

namespace smc::supervision {

std::optional<ModuleId> module_from_letter(std::string_view name) noexcept {
  if (name.size() != 1 || name[0] < 'A' || name[0] >= 'A' + kMaxModules) return std::nullopt;
  return static_cast<ModuleId>(name[0] - 'A');
}

std::string letters(ModuleMask mask) {
  std::string out;
  for (int i = 0; i < kMaxModules; ++i) {
    if ((mask >> i) & 1u) out.push_back(static_cast<char>('A' + i));
  }
  return out;
}

const char* module_name(ModuleId m) noexcept {
  static constexpr const char* kNames[kModuleCount] = {"feedrate routine",
                                                       "operator input monitor",
                                                       "feed hold",
                                                       "operator chatter detector",
                                                       "automatic chatter detector",
                                                       "chatter suppressor",
                                                       "chatter suppression routine",
                                                       "parameter estimator",
                                                       "force signal processor",
                                                       "contact monitor",
                                                       "adaptive force controller",
                                                       "model-based force controller",
                                                       "spindle power monitor",
                                                       "tool-breakage detector",
                                                       "spindle-speed chatter suppressor"};
  const auto i = static_cast<int>(m);
  return i < kModuleCount ? kNames[i] : "";
}

}  // namespace smc::supervision
