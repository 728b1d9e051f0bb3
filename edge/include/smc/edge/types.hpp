#pragma once
// Types shared by the edge's modules, supervisors and drives. Plain data:
// everything here is trivially copyable and safe to use in the loop.

#include <cstdint>

#include "smc/supervision/grafcet_binding.hpp"
#include "smc/supervision/modules.hpp"

namespace smc::edge {

// The supervisory modules' vocabulary (A–L, masks) and the receptivities
// a–h are shared with the cell: services/supervision.
using supervision::bit;
using supervision::has;
using supervision::kInputA;
using supervision::kInputB;
using supervision::kInputC;
using supervision::kInputD;
using supervision::kInputE;
using supervision::kInputF;
using supervision::kInputG;
using supervision::kInputH;
using supervision::kMaxModules;
using supervision::kModuleCount;
using supervision::letter;
using supervision::ModuleId;
using supervision::ModuleMask;
using supervision::Receptivity;

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
  // F_y once more, through a wideband filter of its own rather than
  // F_y's (250 Hz for the force controller, which leaves the tool's mode
  // little of its force): module E estimates the tool-part vibration from
  // it. NaN when the sensor has no such channel; E then judges F_z alone.
  double f_y_wide_n = __builtin_nan("");
  // The same channel where it samples faster than the loop: `wide_count`
  // samples since the last sample period, evenly spaced, oldest first (the
  // last is f_y_wide_n). 0: the channel samples with the loop, f_y_wide_n
  // alone (operation.wideband_samples_per_tick says which E expects).
  static constexpr int kMaxWideSamples = 8;
  int wide_count = 0;
  double f_y_wide_sub_n[kMaxWideSamples] = {};
};

// Operator inputs as last received (module B reads them).
struct OperatorInputs {
  bool feed_hold = false;        // hold requested (true) or released (false)
  uint32_t chatter_signals = 0;  // count of chatter signals received so far
  uint32_t releases = 0;         // count of feed-hold-off commands (clears a fault hold)
};

}  // namespace smc::edge
