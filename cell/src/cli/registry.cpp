#include "registry.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>

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

void print_history(store::Store& s, const std::string& kind, const std::string& id) {
  const auto h = s.history(kind, id);
  std::printf("  history\n");
  if (h.empty()) std::printf("    (none recorded)\n");
  for (const auto& e : h) {
    std::printf("    %s  %-9s by %s: %s%s%s\n", store::format_time(e.time_ms).c_str(),
                e.action.c_str(), e.author.c_str(), e.reason.c_str(), e.detail.empty() ? "" : " — ",
                e.detail.c_str());
  }
}

}  // namespace smc::cell::cli
