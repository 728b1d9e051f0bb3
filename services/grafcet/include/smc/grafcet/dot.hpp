#pragma once
// Graphviz DOT of a Grafcet: steps as boxes (initial steps double), actions
// beside their step, transitions as bars labelled "(n) receptivity" and, where
// a checking order applies, their rank. Offline only.

#include <string>

#include "smc/grafcet/model.hpp"

namespace smc::grafcet {

std::string to_dot(const Grafcet& grafcet);

}  // namespace smc::grafcet
