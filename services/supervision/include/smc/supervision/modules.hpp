#pragma once
// The supervisory modules' vocabulary: the machining modules of the paper's
// Table 1 (A–L) by letter, and the 16-bit mask in which bit i is module i —
// the layout the edge's loop, the configuration's module list and the wire's
// `active_modules` fields all use. Plain data, real-time safe.
//
// "Supervisory modules" are these units of the edge's loop; "machining"
// (services/machining) is the physics. Adding a module: a letter here (the
// next one, up to P), its class in edge/src/modules/, its line in the edge's
// module registry (edge/src/modules/registry.cpp) and its source in
// edge/CMakeLists.txt.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace smc::supervision {

// A–L: the paper's Table 1. M: spindle power monitor (holds the mean spindle
// power per revolution at the limit by scaling F_ref; runs under the state
// supervisor whenever configured, not as a Grafcet action). Beyond the
// paper (edge/README.md, "Modules beyond Table 1"): N, tool-breakage
// detector (per-tooth force, receptivity f); O, spindle-speed chatter
// suppressor (moves the spindle to a stable pocket, receptivities g, h).
enum class ModuleId : uint8_t { A, B, C, D, E, F, G, H, I, J, K, L, M, N, O };
inline constexpr int kModuleCount = 15;       // A–O
inline constexpr int kPaperModuleCount = 12;  // the paper's modules, A–L
inline constexpr int kMaxModules = 16;        // what a ModuleMask can hold, A–P
using ModuleMask = uint16_t;

constexpr ModuleMask bit(ModuleId m) noexcept {
  return static_cast<ModuleMask>(1u << static_cast<unsigned>(m));
}
constexpr char letter(ModuleId m) noexcept { return static_cast<char>('A' + static_cast<int>(m)); }
constexpr bool has(ModuleMask mask, ModuleId m) noexcept { return (mask & bit(m)) != 0; }

// 'A'..'P' → the module; anything else → nullopt.
std::optional<ModuleId> module_from_letter(std::string_view name) noexcept;
// "ABIJ" for a mask; "" for 0.
std::string letters(ModuleMask mask);
// The name of a module (Table 1's for A–L), e.g. "feedrate routine"; "" past M.
const char* module_name(ModuleId m) noexcept;

}  // namespace smc::supervision
