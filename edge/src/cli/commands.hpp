#pragma once
// smc-edge subcommands.

#include <stdexcept>
#include <string>

namespace CLI {
class App;
}

namespace smc::edge::cli {

struct Failure : std::runtime_error {
  Failure(int code, const std::string& message) : std::runtime_error(message), exit_code(code) {}
  int exit_code;
};

void add_simulate(CLI::App& app);
void add_check(CLI::App& app);
void add_run(CLI::App& app);
#if SMC_HAVE_LINUXCNC
void add_hal(CLI::App& app);
void add_hal_latency(CLI::App& app);
#endif

}  // namespace smc::edge::cli
