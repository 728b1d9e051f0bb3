#pragma once
// Subcommand registry for smc-cell. Each src/cli/cmd_*.cpp adds its
// subcommands with:
//
//   SMC_CELL_COMMAND(lobes) {           // body receives CLI::App& app
//     auto* sub = app.add_subcommand("lobes", "...");
//     ...
//   }
//
// A subcommand's callback returns normally on success and throws
// smc::cell::cli::Failure (exit code, message) on user errors.

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace CLI {
class App;
}
namespace smc::cell::store {
class Store;
}

namespace smc::cell::cli {

using Registrar = void (*)(CLI::App& app);

std::vector<std::pair<int, Registrar>>& registry();

struct Register {
  Register(int order, Registrar r) { registry().emplace_back(order, r); }
};

// Thrown by a subcommand to end with a message and an exit code.
struct Failure : std::runtime_error {
  Failure(int code, const std::string& message) : std::runtime_error(message), exit_code(code) {}
  int exit_code;
};

// --db FILE, defaulting to $SMC_CELL_DB or ./smc-cell.db.
void add_db_option(CLI::App* cmd, std::string& db);

// "  history" and one line per change of a catalog entity (time, action,
// author, reason, what changed).
void print_history(store::Store& s, const std::string& kind, const std::string& id);

}  // namespace smc::cell::cli

// `order` sorts subcommands in --help.
#define SMC_CELL_COMMAND(name, order)                                                              \
  static void smc_cell_register_##name(CLI::App& app);                                             \
  static const ::smc::cell::cli::Register smc_cell_register_obj_##name(order,                      \
                                                                       &smc_cell_register_##name); \
  static void smc_cell_register_##name(CLI::App& app)
