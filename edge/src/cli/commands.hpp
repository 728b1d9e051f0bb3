#pragma once
// smc-edge subcommands.

#include <stdexcept>
#include <string>

namespace CLI {
class App;
}
namespace smc::config {
class SimulatedMill;
}

namespace smc::edge::cli {

struct Failure : std::runtime_error {
  Failure(int code, const std::string& message) : std::runtime_error(message), exit_code(code) {}
  int exit_code;
};

// --break-tooth T@S or T@S:MM (tooth from 1, machine time in s, edge lost in
// mm; 0 or none: the whole edge) as simulation.tooth_breaks; Failure(2)
// naming the option on a bad spec.
void add_tooth_break(const std::string& spec, smc::config::SimulatedMill& sim);

void add_simulate(CLI::App& app);
void add_check(CLI::App& app);
void add_run(CLI::App& app);
#if SMC_HAVE_LINUXCNC
void add_hal(CLI::App& app);
void add_hal_latency(CLI::App& app);
#endif

}  // namespace smc::edge::cli
