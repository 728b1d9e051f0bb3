#pragma once
// The HTTP side: one I/O thread running Boost.Beast/Asio. Every connection
// is asynchronous, so one thread serves any number of page loads, REST calls
// and push-stream clients without one client ever waiting on another.
// Stream clients each get a bounded queue that drops the oldest events when
// the client does not keep up (counted, and told to the client); a client
// whose socket has accepted nothing for `stall_timeout` is disconnected.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "event.hpp"

namespace smc::dashboard {

class Api;
class CellState;

struct HttpOptions {
  std::string address = "127.0.0.1";
  std::uint16_t port = 8080;  // 0: any free port (see HttpServer::port())
  std::size_t max_connections = 256;
  std::size_t max_streams = 64;
  std::size_t stream_queue_events = 1024;  // per stream client, oldest dropped beyond
  int stream_send_buffer = 128 * 1024;     // SO_SNDBUF of stream sockets (bytes)
  std::chrono::milliseconds stall_timeout{30000};
  std::chrono::milliseconds heartbeat{15000};
  std::chrono::milliseconds idle_timeout{30000};  // keep-alive REST connections
  std::size_t max_body = 4096;                    // request body, bytes
  std::size_t max_header = 8192;                  // request header, bytes
  // HTTPS: the server's certificate chain and its key (PEM files). Both or
  // neither; with them the server speaks TLS 1.2+ only.
  std::string tls_cert;
  std::string tls_key;
};

class HttpServer final : public EventSink {
 public:
  // Throws when the TLS certificate or key cannot be used (naming the file).
  HttpServer(HttpOptions options, Api& api, CellState& state);
  ~HttpServer() override;
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds and listens (throws std::runtime_error naming the address when it
  // cannot), then starts the I/O thread.
  void start();
  void stop() noexcept;
  std::uint16_t port() const noexcept;
  bool tls() const noexcept;  // speaks HTTPS

  // Any thread; never blocks: the event is handed to the I/O thread.
  void publish(Event event) override;

  // JSON of the stream clients and counters. Call on the I/O thread (the
  // Api calls it from a request handler).
  std::string stats_json() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::dashboard
