// smc-cell: the cell service of the supervisory machining cell, and its
// offline tools. Thin: flag parsing only; each subcommand calls a library.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <string>

#include "registry.hpp"
#include "smc/common/log.hpp"
#include "smc/transport/endpoint.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "smc-cell: cell service of a supervisory machining cell (SMC I / SMC II over DDS),\n"
      "and its offline tools for planning, stability analysis and supervisor checks."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Show help for every subcommand");
  smc::log::Options log_opts{.name = "smc-cell"};
  app.add_option("--log-level", log_opts.level,
                 "trace|debug|info|warn|error|critical|off (default: $SMC_LOG_LEVEL or info)");
  app.add_option("--log-format", log_opts.format,
                 "spdlog pattern, or 'json' (default: $SMC_LOG_FORMAT)");
  auto& reg = smc::cell::cli::registry();
  std::stable_sort(reg.begin(), reg.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [order, r] : reg) r(app);
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
  } catch (const smc::cell::cli::Failure& f) {
    std::fprintf(stderr, "smc-cell: %s\n", f.what());
    return f.exit_code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-cell: error: %s\n", e.what());
    return 1;
  }
  smc::log::shutdown();
  return 0;
}
