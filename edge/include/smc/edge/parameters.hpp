#pragma once
// The fixed machine and operation parameter modules (paper, design step 2)
// as the edge's modules read them. Defined with the cell in
// services/supervision, which reads and checks them from a configuration.

#include "smc/supervision/parameters.hpp"

namespace smc::edge {

using EdgeParameters = supervision::Parameters;
using supervision::ConfigError;
using supervision::parameters_from_config;

}  // namespace smc::edge
