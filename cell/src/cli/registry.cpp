#include "registry.hpp"

#include <CLI/CLI.hpp>

#include "smc/cell/store/store.hpp"

namespace smc::cell::cli {

namespace store = smc::cell::store;

std::vector<std::pair<int, Registrar>>& registry() {
  static std::vector<std::pair<int, Registrar>> r;
  return r;
}

void add_db_option(CLI::App* cmd, std::string& db) {
  db = store::default_db_path();
  cmd->add_option("--db", db, "Cell database file (default: $SMC_CELL_DB or ./smc-cell.db)")
      ->capture_default_str();
}

}  // namespace smc::cell::cli
