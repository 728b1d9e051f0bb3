#pragma once
// smc-dashboard as a library: DDS (every live topic of the cell) -> state ->
// HTTP (the page, a REST API, a Server-Sent Events stream) and operator
// commands back onto DDS. main() parses flags and calls run(); tests start a
// Dashboard in-process on a free port and a partition of their own.
//
// Boundary policy. The dashboard is a view: it never ends because of what it
// receives. A malformed document is counted and dropped; a failing DDS call
// in the loop is logged and the loop goes on after 100 ms; a bad HTTP
// request gets a 4xx naming what is wrong; an operator command that cannot be
// written is answered as failed to its sender. Only failing to create the
// participant or to bind the HTTP port at start-up ends the process.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

namespace smc::dashboard {

struct Options {
  std::string http = "127.0.0.1:8080";  // HOST:PORT to listen on; port 0 picks a free one
  std::uint32_t domain_id = 0;
  std::string partition;   // DDS partition (empty: the default one)
  std::string dds_config;  // Cyclone DDS XML or file://; empty: CYCLONEDDS_URI or loopback
  std::string token_file;  // "NAME sha256:HEX" lines; empty: read-only dashboard
  std::string web_root;    // serve the page from this folder instead of the embedded copy
  std::string cell_db;     // the cell's SQLite database: job history pages; empty: none
  // HTTPS: certificate chain and key (PEM); both or neither. Empty: HTTP.
  std::string tls_cert;
  std::string tls_key;

  std::size_t max_streams = 64;
  std::size_t stream_queue_events = 1024;  // per stream client; oldest dropped beyond
  int stream_send_buffer = 128 * 1024;     // bytes of kernel buffer per stream client
  std::chrono::milliseconds stall_timeout{30000};
  std::chrono::milliseconds heartbeat{15000};
  std::size_t max_body = 4096;
};

// "HOST:PORT" or "[V6]:PORT" -> host and port; throws std::invalid_argument.
std::pair<std::string, std::uint16_t> parse_listen_address(std::string_view text);

class Dashboard {
 public:
  // Reads the token file and creates the DDS entities; throws on a bad
  // token file (file:line: what) or a DDS failure.
  explicit Dashboard(const Options& options);
  ~Dashboard();
  Dashboard(const Dashboard&) = delete;
  Dashboard& operator=(const Dashboard&) = delete;

  // Listens (throws when it cannot) and starts the DDS and I/O threads.
  void start();
  void stop() noexcept;

  std::uint16_t port() const noexcept;
  std::string url() const;  // http://HOST:PORT/, or https:// with a certificate

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// start(), print "smc-dashboard: listening on URL" on stdout, wait for
// SIGINT or SIGTERM, stop(). Returns the process exit code.
int run(const Options& options);

// The --token-file line of operator `name` with this token: "NAME
// sha256:HEX" (the file holds the token's SHA-256, never the token).
// Throws std::invalid_argument naming what is wrong with either.
std::string hash_token_line(std::string_view name, std::string_view token);

}  // namespace smc::dashboard
