#pragma once
// Basic types of smc_grafcet, for headers that need no more (engine.hpp).

#include <cstddef>
#include <cstdint>

namespace smc::grafcet {

// A set of steps, inputs or actions: bit i = the item with index i in
// declaration order.
using Mask = std::uint64_t;

inline constexpr std::size_t kMaxSteps = 64;
inline constexpr std::size_t kMaxInputs = 64;
inline constexpr std::size_t kMaxActions = 64;

class Grafcet;

}  // namespace smc::grafcet
