#pragma once
// Types shared by the edge's modules, supervisors and drives. Plain data:
// everything here is trivially copyable and safe to use in the loop.

#include <cstdint>

namespace smc::edge {

// The paper's machining modules (Table 1). Bit i of a ModuleMask is module i.
enum class ModuleId : uint8_t { A, B, C, D, E, F, G, H, I, J, K, L };
inline constexpr int kModuleCount = 12;
using ModuleMask = uint16_t;

constexpr ModuleMask bit(ModuleId m) noexcept {
  return static_cast<ModuleMask>(1u << static_cast<unsigned>(m));
}
constexpr char letter(ModuleId m) noexcept { return static_cast<char>('A' + static_cast<int>(m)); }

// Result of a real-time call: never an exception on the loop.
enum class Status : uint8_t { kOk, kError };

// Why the core put the machine in feed hold on its own.
enum class Fault : uint8_t {
  kNone,
  kNonFiniteForce,   // NaN or infinite force sample
  kSaturatedForce,   // force beyond the sensor's range
  kModuleError,      // a module's update returned kError
  kOverrun,          // the real-time loop missed its deadline
  kSupervisorError,  // the Grafcet did not reach a stable situation
  kDriveError,       // the drive reported an error
};
const char* to_string(Fault f) noexcept;

// One sensor sample (every sample period, 0.5 ms).
struct ForceSample {
  double t_s = 0;  // machine time
  double f_x_n = 0;
  double f_y_n = 0;  // after the F_y anti-alias filter
  double f_z_n = 0;  // after the F_z anti-alias filter
};

// Operator inputs as last received (module B reads them).
struct OperatorInputs {
  bool feed_hold = false;        // hold requested (true) or released (false)
  uint32_t chatter_signals = 0;  // count of chatter signals received so far
  uint32_t releases = 0;         // count of feed-hold-off commands (clears a fault hold)
};

// Receptivity inputs of the operation supervisor (paper Table 2).
enum Receptivity : uint8_t {
  kInputA = 0,  // a: operator feed hold active
  kInputB = 1,  // b: tool-part contact
  kInputC = 2,  // c: chatter signalled by the operator
  kInputD = 3,  // d: chatter detected automatically
  kInputE = 4,  // e: chatter suppression routine complete
};

}  // namespace smc::edge
