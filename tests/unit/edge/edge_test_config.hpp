#pragma once
// The shipped configurations, for tests.

#include <string>

#include "smc/documents/load.hpp"
#include "smc/edge/parameters.hpp"
#include "smc_config.pb.h"

namespace smc::edge::test {

inline std::string source_path(const std::string& rel) {
  return std::string(SMC_SOURCE_DIR) + "/" + rel;
}

inline smc::config::SupervisorConfig shipped_config(const std::string& name) {
  return smc::documents::load_supervisor_config(source_path("edge/configs/" + name));
}

inline EdgeParameters paper_parameters() {
  return parameters_from_config(shipped_config("smc2.textproto"));
}

}  // namespace smc::edge::test
