// smc-edge: the edge process of one mill, and its offline tools.
// Thin: flags only; everything else is in the smc_edge library.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"
#include "smc/common/log.hpp"
#include "smc/transport/endpoint.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "smc-edge: the edge process of a mill under supervisory machining control.\n"
      "Runs machining modules A-L under a state supervisor and a Grafcet operation\n"
      "supervisor, on a simulated mill or a recorded force file."};
  app.require_subcommand(1);
  smc::log::Options log_opts{.name = "smc-edge"};
  app.add_option("--log-level", log_opts.level,
                 "trace|debug|info|warn|error|critical|off (default: $SMC_LOG_LEVEL or info)");
  app.add_option("--log-format", log_opts.format, "spdlog pattern, or 'json'");
  smc::edge::cli::add_simulate(app);
  smc::edge::cli::add_check(app);
  smc::edge::cli::add_run(app);
#if SMC_HAVE_LINUXCNC
  smc::edge::cli::add_hal(app);
  smc::edge::cli::add_hal_latency(app);
#endif
  app.parse_complete_callback([&] {
    smc::log::init(log_opts);
    // A sample a machine's writer sent about another machine (refused).
    smc::transport::set_refusal_handler(
        [](const std::string& what) { spdlog::warn("dds: {}", what); });
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const smc::edge::cli::Failure& f) {
    std::fprintf(stderr, "smc-edge: %s\n", f.what());
    return f.exit_code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-edge: error: %s\n", e.what());
    return 1;
  }
  smc::log::shutdown();
  return 0;
}
