// smc-dashboard: live force, chatter and supervisor state of the cell in a
// browser, with operator commands. Thin: flags only; the rest is the
// smc_dashboard library.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include "smc/common/log.hpp"
#include "smc/dashboard/dashboard.hpp"
#include "smc/transport/endpoint.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "smc-dashboard: subscribes to every live topic of the cell (force, chatter, supervisor\n"
      "state, jobs) and serves a web page, a REST API and a Server-Sent Events stream.\n"
      "Operators holding a token may request feed holds and signal chatter."};
  smc::dashboard::Options o;
  smc::log::Options log_opts{.name = "smc-dashboard"};
  long long stall_ms = o.stall_timeout.count();
  app.add_option("--http", o.http, "HOST:PORT to listen on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--domain", o.domain_id, "DDS domain id")->capture_default_str();
  app.add_option("--partition", o.partition, "DDS partition (default: the default partition)");
  app.add_option("--dds-config", o.dds_config,
                 "Cyclone DDS XML or file://PATH (default: $CYCLONEDDS_URI, else loopback)");
  app.add_option("--cell-db", o.cell_db,
                 "The cell's SQLite database (smc-cell serve --db), read on each job history "
                 "page and CSV export (opened on the first; it may not exist yet at start)");
  app.add_option("--token-file", o.token_file,
                 "operator tokens, one 'NAME sha256:HEX' line each (--hash-token writes one; "
                 "without the file: read-only)")
      ->check(CLI::ExistingFile);
  app.add_option("--tls-cert", o.tls_cert,
                 "HTTPS: the server's certificate chain (PEM; deploy/security/pki.sh https "
                 "makes one); with --tls-key")
      ->check(CLI::ExistingFile);
  app.add_option("--tls-key", o.tls_key, "HTTPS: the certificate's key (PEM)")
      ->check(CLI::ExistingFile);
  std::string hash_for;
  app.add_option("--hash-token", hash_for,
                 "read a token from stdin and print NAME's line for --token-file, then exit")
      ->option_text("NAME");
  app.add_option("--web-root", o.web_root,
                 "serve the page from this folder instead of the embedded copy")
      ->check(CLI::ExistingDirectory);
  app.add_option("--max-streams", o.max_streams, "most concurrent stream clients")
      ->capture_default_str();
  app.add_option("--stream-queue", o.stream_queue_events,
                 "events queued per stream client before the oldest are dropped")
      ->capture_default_str()
      ->check(CLI::Range(1, 1 << 20));
  app.add_option("--stall-timeout-ms", stall_ms,
                 "disconnect a stream client whose socket accepts nothing for this long")
      ->capture_default_str()
      ->check(CLI::Range(100LL, 3600000LL));
  app.add_option("--log-level", log_opts.level,
                 "trace|debug|info|warn|error|critical|off (default: $SMC_LOG_LEVEL or info)");
  app.add_option("--log-format", log_opts.format, "spdlog pattern, or 'json'");
  try {
    app.parse(argc, argv);
    if (!hash_for.empty()) {
      std::string token;
      std::getline(std::cin, token);
      std::printf("%s\n", smc::dashboard::hash_token_line(hash_for, token).c_str());
      return 0;
    }
    smc::log::init(log_opts);
    // A sample a machine's writer sent about another machine (refused).
    smc::transport::set_refusal_handler(
        [](const std::string& what) { spdlog::warn("dds: {}", what); });
    o.stall_timeout = std::chrono::milliseconds(stall_ms);
    const int rc = smc::dashboard::run(o);
    smc::log::shutdown();
    return rc;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-dashboard: error: %s\n", e.what());
    return 1;
  }
}
