#include "registry.hpp"

namespace smc::cell::cli {

std::vector<std::pair<int, Registrar>>& registry() {
  static std::vector<std::pair<int, Registrar>> r;
  return r;
}

}  // namespace smc::cell::cli
