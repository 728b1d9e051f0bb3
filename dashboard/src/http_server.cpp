#include "http_server.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <optional>
#include <thread>
#include <type_traits>
#include <vector>

#include "api.hpp"
#include "cell_state.hpp"
#include "json.hpp"
#include "smc/dashboard/drop_oldest_queue.hpp"

namespace smc::dashboard {

namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;
using Frame = std::shared_ptr<const std::string>;
// A connection: plain TCP, or TLS over it (HttpOptions::tls_cert).
using PlainStream = beast::tcp_stream;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

template <class S>
tcp::socket& socket_of(S& s) {
  return beast::get_lowest_layer(s).socket();
}

constexpr std::size_t kMaxFramesPerWrite = 64;  // one gathered write

std::string endpoint_text(const tcp::socket& s) {
  beast::error_code ec;
  const auto ep = s.remote_endpoint(ec);
  if (ec) return "?";
  return ep.address().to_string() + ":" + std::to_string(ep.port());
}

std::string to_std(beast::string_view v) { return std::string(v.data(), v.size()); }

Frame make_frame(std::string s) { return std::make_shared<const std::string>(std::move(s)); }

}  // namespace

// ------------------------------------------------------------------ streams --

// A stream client, whatever its connection (StreamSession<S>).
class StreamClient {
 public:
  virtual ~StreamClient() = default;
  virtual std::uint64_t id() const = 0;
  virtual bool wants(const Event& e) const = 0;
  virtual void push(Frame f) = 0;
  virtual bool stalled(Clock::time_point now, std::chrono::milliseconds timeout) const = 0;
  virtual void close() = 0;
  virtual void write_stats(JsonWriter& w, Clock::time_point now) const = 0;
};

// All stream clients; lives on the I/O thread.
class Hub {
 public:
  explicit Hub(const HttpOptions& o) : options_(o) {}
  void add(std::shared_ptr<StreamClient> s) { sessions_.push_back(std::move(s)); }
  void remove(const StreamClient* s) {
    std::erase_if(sessions_, [s](const auto& p) { return p.get() == s; });
  }
  void broadcast(const Event& e);
  void tick(Clock::time_point now);  // stalls and heartbeats
  void close_all();
  std::size_t size() const { return sessions_.size(); }
  void write_stats(JsonWriter& w, Clock::time_point now) const;
  std::uint64_t next_id() { return ++last_id_; }

  const HttpOptions& options_;
  std::uint64_t broadcast_ = 0;
  std::uint64_t closed_stalled_ = 0;
  std::uint64_t dropped_closed_ = 0;  // dropped by clients that have gone

 private:
  std::vector<std::shared_ptr<StreamClient>> sessions_;
  Clock::time_point last_heartbeat_ = Clock::now();
  std::uint64_t last_id_ = 0;
};

template <class S>
class StreamSession final : public StreamClient,
                            public std::enable_shared_from_this<StreamSession<S>> {
 public:
  StreamSession(S stream, StreamRequest filter, Hub& hub, std::string remote)
      : socket_(std::move(stream)),
        filter_(std::move(filter)),
        hub_(hub),
        queue_(hub.options_.stream_queue_events),
        id_(hub.next_id()),
        remote_(std::move(remote)),
        connected_(Clock::now()) {}

  std::uint64_t id() const override { return id_; }

  void start(Frame header, Frame hello) {
    beast::error_code ec;
    // The request's timeout no longer applies: the hub watches for stalls.
    beast::get_lowest_layer(socket_).expires_never();
    socket_of(socket_).set_option(tcp::no_delay(true), ec);
    socket_of(socket_).set_option(
        asio::socket_base::send_buffer_size(hub_.options_.stream_send_buffer), ec);
    inflight_.push_back(std::move(header));  // never dropped: written first
    queue_.push(std::move(hello));
    pump();
    watch_for_close();
  }

  bool wants(const Event& e) const override {
    if (e.kind == EventKind::kBatch && !filter_.raw) return false;
    if (filter_.mills.empty() || e.mill.empty()) return true;
    return std::find(filter_.mills.begin(), filter_.mills.end(), e.mill) != filter_.mills.end();
  }

  void push(Frame f) override {
    if (closed_) return;
    queue_.push(std::move(f));
    pump();
  }

  // Closes a client whose socket has accepted nothing for `timeout`.
  bool stalled(Clock::time_point now, std::chrono::milliseconds timeout) const override {
    return writing_ && now - write_started_ > timeout;
  }

  void close() override {
    if (closed_) return;
    closed_ = true;
    beast::error_code ec;
    socket_of(socket_).shutdown(tcp::socket::shutdown_both, ec);
    socket_of(socket_).close(ec);
    hub_.dropped_closed_ += queue_.dropped();
    // The hub may be iterating its sessions: remove after this handler.
    asio::post(socket_.get_executor(),
               [self = this->shared_from_this()] { self->hub_.remove(self.get()); });
  }

  void write_stats(JsonWriter& w, Clock::time_point now) const override {
    w.begin_object()
        .field("id", id_)
        .field("remote", remote_)
        .field("raw", filter_.raw)
        .field("queued", queue_.size())
        .field("sent", sent_)
        .field("dropped", queue_.dropped())
        .field("writing", writing_)
        .field("connected_s", std::chrono::duration<double>(now - connected_).count());
    w.key("mills").begin_array();
    for (const auto& m : filter_.mills) w.value(m);
    w.end_array().end_object();
  }

 private:
  void pump() {
    if (closed_ || writing_) return;
    if (queue_.dropped() != dropped_reported_) {  // tell the client what it missed
      JsonWriter w;
      w.begin_object()
          .field("dropped", queue_.dropped() - dropped_reported_)
          .field("dropped_total", queue_.dropped())
          .end_object();
      dropped_reported_ = queue_.dropped();
      inflight_.push_back(make_frame("event: dropped\ndata: " + w.str() + "\n\n"));
    }
    while (!queue_.empty() && inflight_.size() < kMaxFramesPerWrite) {
      inflight_.push_back(queue_.pop());
    }
    if (inflight_.empty()) return;
    buffers_.clear();
    for (const auto& f : inflight_) buffers_.emplace_back(f->data(), f->size());
    writing_ = true;
    write_started_ = Clock::now();
    asio::async_write(socket_, buffers_,
                      [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
                        self->writing_ = false;
                        self->sent_ += self->inflight_.size();
                        self->inflight_.clear();
                        if (ec) {
                          self->close();
                          return;
                        }
                        self->pump();
                      });
  }

  // A stream client sends nothing after its request: any read completing
  // (end of file, data, error) means it has gone.
  void watch_for_close() {
    socket_.async_read_some(asio::buffer(discard_),
                            [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
                              if (ec) {
                                self->close();
                              } else {
                                self->watch_for_close();
                              }
                            });
  }

  S socket_;
  StreamRequest filter_;
  Hub& hub_;
  DropOldestQueue<Frame> queue_;
  std::vector<Frame> inflight_;
  std::vector<asio::const_buffer> buffers_;
  bool writing_ = false;
  bool closed_ = false;
  Clock::time_point write_started_;
  std::uint64_t sent_ = 0;
  std::uint64_t dropped_reported_ = 0;
  std::uint64_t id_;
  std::string remote_;
  Clock::time_point connected_;
  char discard_[256];
};

void Hub::broadcast(const Event& e) {
  ++broadcast_;
  // Sessions close asynchronously (removal is posted), so indices stay valid.
  for (std::size_t i = 0; i < sessions_.size(); ++i) {
    auto& s = sessions_[i];
    if (s->wants(e)) s->push(e.frame);
  }
}

void Hub::tick(Clock::time_point now) {
  std::vector<std::shared_ptr<StreamClient>> stalled;
  for (const auto& s : sessions_) {
    if (s->stalled(now, options_.stall_timeout)) stalled.push_back(s);
  }
  for (const auto& s : stalled) {
    ++closed_stalled_;
    spdlog::warn("stream client {} accepted nothing for {} ms: disconnected", s->id(),
                 options_.stall_timeout.count());
    s->close();
  }
  if (now - last_heartbeat_ >= options_.heartbeat) {
    last_heartbeat_ = now;
    const Frame beat = make_frame(": heartbeat\n\n");
    for (const auto& s : sessions_) s->push(beat);
  }
}

void Hub::close_all() {
  const auto copy = sessions_;
  for (const auto& s : copy) s->close();
}

void Hub::write_stats(JsonWriter& w, Clock::time_point now) const {
  w.key("streams").begin_array();
  for (const auto& s : sessions_) s->write_stats(w, now);
  w.end_array();
  w.field("events_broadcast", broadcast_)
      .field("streams_closed_stalled", closed_stalled_)
      .field("dropped_by_departed_streams", dropped_closed_);
}

// --------------------------------------------------------------- REST/HTTP --

// Everything the connections share; owned by HttpServer, used on the I/O
// thread (except `port`).
struct ServerCore {
  ServerCore(HttpOptions o, Api& a, CellState& s)
      : options(std::move(o)),
        api(a),
        state(s),
        acceptor(ioc),
        timer(ioc),
        accept_retry(ioc),
        hub(options) {}

  HttpOptions options;
  Api& api;
  CellState& state;
  // Set when the server speaks HTTPS (options.tls_cert).
  std::optional<asio::ssl::context> tls;
  asio::io_context ioc{1};
  tcp::acceptor acceptor;
  asio::steady_timer timer;
  asio::steady_timer accept_retry;
  Hub hub;
  std::thread thread;
  std::atomic<std::uint16_t> port{0};
  std::size_t connections = 0;  // I/O thread
  std::uint64_t requests = 0;   // I/O thread
  bool stopping = false;        // I/O thread

  std::uint64_t tls_handshakes_failed = 0;  // I/O thread

  void accept();
  void schedule_tick();
  template <class S>
  void open_stream(S stream, StreamRequest filter, std::string remote);
};

namespace {

template <class S>
class HttpSession : public std::enable_shared_from_this<HttpSession<S>> {
 public:
  // Plain: the stream is the socket; TLS: a TLS stream over it.
  template <class... TlsContext>
  HttpSession(tcp::socket socket, ServerCore& server, TlsContext&... tls)
      : stream_(beast::tcp_stream(std::move(socket)), tls...),
        server_(server),
        remote_(endpoint_text(socket_of(stream_))) {
    ++server_.connections;
  }
  ~HttpSession() { --server_.connections; }

  // The TLS handshake first, when there is one, then the first request. A
  // client that speaks plain HTTP to the HTTPS port is told so, in plain
  // HTTP, and closed.
  void start() {
    if constexpr (std::is_same_v<S, TlsStream>) {
      beast::get_lowest_layer(stream_).expires_after(server_.options.idle_timeout);
      beast::async_detect_ssl(beast::get_lowest_layer(stream_), buffer_,
                              [self = this->shared_from_this()](beast::error_code ec, bool is_tls) {
                                if (ec) {
                                  self->close();
                                } else if (!is_tls) {
                                  self->refuse_plain();
                                } else {
                                  self->handshake();
                                }
                              });
    } else {
      read();
    }
  }

 private:
  void handshake() {
    stream_.async_handshake(
        asio::ssl::stream_base::server, buffer_.data(),
        [self = this->shared_from_this()](beast::error_code ec, std::size_t used) {
          if (ec) {
            // A scanner, or a browser that does not trust the certificate.
            ++self->server_.tls_handshakes_failed;
            spdlog::debug("https: handshake with {} failed: {}", self->remote_, ec.message());
            self->close();
            return;
          }
          self->buffer_.consume(used);
          self->read();
        });
  }

  void refuse_plain() {
    ++server_.tls_handshakes_failed;
    static const std::string kRefusal =
        "HTTP/1.1 400 Bad Request\r\nContent-Type: text/plain; charset=utf-8\r\n"
        "Connection: close\r\nContent-Length: 48\r\n\r\n"
        "This dashboard speaks HTTPS only: use https://.\n";
    asio::async_write(
        beast::get_lowest_layer(stream_), asio::buffer(kRefusal),
        [self = this->shared_from_this()](beast::error_code, std::size_t) { self->close(); });
  }

 public:
  void read() {
    parser_.emplace();
    parser_->body_limit(server_.options.max_body);
    parser_->header_limit(static_cast<std::uint32_t>(server_.options.max_header));
    beast::get_lowest_layer(stream_).expires_after(server_.options.idle_timeout);
    http::async_read(stream_, buffer_, *parser_,
                     [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
                       self->on_read(ec);
                     });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == asio::error::eof || ec == beast::error::timeout ||
        ec == asio::error::operation_aborted || ec == asio::error::connection_reset ||
        ec == asio::ssl::error::stream_truncated) {
      close();
      return;
    }
    if (ec == http::error::body_limit) {
      send(error_response(413, "request body larger than " +
                                   std::to_string(server_.options.max_body) + " bytes"),
           false);
      return;
    }
    if (ec == http::error::header_limit) {
      send(error_response(431, "request header larger than " +
                                   std::to_string(server_.options.max_header) + " bytes"),
           false);
      return;
    }
    if (ec) {
      send(error_response(400, "malformed HTTP request: " + ec.message()), false);
      return;
    }
    ++server_.requests;
    auto& req = parser_->get();
    HttpRequest r;
    r.method = to_std(req.method_string());
    r.target = to_std(req.target());
    r.authorization = to_std(req[http::field::authorization]);
    r.content_type = to_std(req[http::field::content_type]);
    r.body = std::move(req.body());
    r.remote = remote_;
    keep_alive_ = req.keep_alive();

    if (Api::is_stream(r)) {
      auto parsed = server_.api.stream_request(r);
      if (auto* err = std::get_if<HttpResponse>(&parsed)) {
        send(std::move(*err), keep_alive_);
        return;
      }
      if (server_.hub.size() >= server_.options.max_streams || server_.stopping) {
        send(error_response(503, "too many stream clients (" +
                                     std::to_string(server_.options.max_streams) + ")"),
             false);
        return;
      }
      server_.open_stream(std::move(stream_), std::get<StreamRequest>(std::move(parsed)), remote_);
      return;
    }
    try {
      server_.api.handle(r, [self = this->shared_from_this()](HttpResponse res) {
        // May run on the DDS thread (operator commands): back to the I/O thread.
        asio::post(self->stream_.get_executor(), [self, res = std::move(res)]() mutable {
          self->send(std::move(res), self->keep_alive_);
        });
      });
    } catch (const std::exception& e) {
      spdlog::error("http: {} {} failed: {}", r.method, r.target, e.what());
      send(error_response(500, "internal error; see the dashboard's log"), false);
    }
  }

  void send(HttpResponse res, bool keep_alive) {
    auto msg = std::make_shared<http::response<http::string_body>>(
        static_cast<http::status>(res.status), 11);
    msg->set(http::field::server, "smc-dashboard");
    msg->set(http::field::content_type, res.content_type);
    msg->set("X-Content-Type-Options", "nosniff");
    msg->set("Referrer-Policy", "no-referrer");
    msg->set("X-Frame-Options", "DENY");
    if (res.content_type.rfind("text/html", 0) == 0) {
      msg->set("Content-Security-Policy",
               "default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
               "connect-src 'self'; frame-ancestors 'none'");
    }
    msg->set(http::field::cache_control,
             res.content_type.rfind("application/json", 0) == 0 ? "no-store" : "no-cache");
    for (const auto& [k, v] : res.headers) msg->set(k, v);
    msg->body() = std::move(res.body);
    msg->keep_alive(keep_alive);
    msg->prepare_payload();
    beast::get_lowest_layer(stream_).expires_after(server_.options.idle_timeout);
    http::async_write(
        stream_, *msg,
        [self = this->shared_from_this(), msg, keep_alive](beast::error_code ec, std::size_t) {
          if (ec) {
            self->close();
          } else if (keep_alive && !self->server_.stopping) {
            self->read();
          } else {
            self->linger();
          }
        });
  }

  // Closing with unread request bytes would reset the connection and could
  // destroy the answer before the client reads it (a 413 to a large body):
  // stop sending, read and discard what the client still sends, then close.
  // Over TLS the bytes still to come are records; half-closing the socket
  // under them would corrupt the stream: end the TLS session, then close.
  void linger() {
    if constexpr (std::is_same_v<S, TlsStream>) {
      beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(2));
      stream_.async_shutdown(
          [self = this->shared_from_this()](beast::error_code) { self->close(); });
      return;
    } else {
      linger_plain();
    }
  }
  void linger_plain() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.expires_after(std::chrono::seconds(2));
    stream_.async_read_some(asio::buffer(discard_),
                            [self = this->shared_from_this()](beast::error_code e, std::size_t) {
                              if (e || ++self->lingered_ > 4096) {
                                self->close();
                              } else {
                                self->linger_more();
                              }
                            });
  }
  void linger_more() {
    stream_.async_read_some(asio::buffer(discard_),
                            [self = this->shared_from_this()](beast::error_code e, std::size_t) {
                              if (e || ++self->lingered_ > 4096) {
                                self->close();
                              } else {
                                self->linger_more();
                              }
                            });
  }

  void close() {
    beast::error_code ec;
    socket_of(stream_).shutdown(tcp::socket::shutdown_both, ec);
    socket_of(stream_).close(ec);
  }

  S stream_;
  ServerCore& server_;
  std::string remote_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  bool keep_alive_ = false;
  std::size_t lingered_ = 0;
  char discard_[4096];
};

}  // namespace

void ServerCore::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || stopping) return;
    if (!ec) {
      if (connections >= options.max_connections) {
        spdlog::warn("http: {} connections open; refusing {}", connections, endpoint_text(socket));
        beast::error_code ignored;
        socket.close(ignored);
      } else if (tls) {
        std::make_shared<HttpSession<TlsStream>>(std::move(socket), *this, *tls)->start();
      } else {
        std::make_shared<HttpSession<PlainStream>>(std::move(socket), *this)->start();
      }
    } else {
      // Out of file descriptors, say: try again shortly rather than spin.
      spdlog::warn("http: accept failed: {}", ec.message());
      accept_retry.expires_after(std::chrono::milliseconds(100));
      accept_retry.async_wait([this](beast::error_code e) {
        if (!e && !stopping) accept();
      });
      return;
    }
    accept();
  });
}

void ServerCore::schedule_tick() {
  timer.expires_after(std::chrono::milliseconds(250));
  timer.async_wait([this](beast::error_code ec) {
    if (ec || stopping) return;
    hub.tick(Clock::now());
    schedule_tick();
  });
}

template <class S>
void ServerCore::open_stream(S stream, StreamRequest filter, std::string remote) {
  auto session = std::make_shared<StreamSession<S>>(std::move(stream), std::move(filter), hub,
                                                    std::move(remote));
  // The page's starting point, taken on this thread in the same handler that
  // subscribes the client: every later change reaches it as an event.
  JsonWriter w;
  w.begin_object()
      .field("stream_id", session->id())
      .field("queue_capacity", options.stream_queue_events)
      .key("cell")
      .raw(state.cell_json())
      .end_object();
  static const Frame kHeader = make_frame(
      "HTTP/1.1 200 OK\r\n"
      "Server: smc-dashboard\r\n"
      "Content-Type: text/event-stream; charset=utf-8\r\n"
      "Cache-Control: no-store\r\n"
      "X-Accel-Buffering: no\r\n"
      "X-Content-Type-Options: nosniff\r\n"
      "Connection: close\r\n"
      "\r\n"
      "retry: 2000\n\n");
  hub.add(session);
  session->start(kHeader, make_frame("event: hello\ndata: " + w.str() + "\n\n"));
}

struct HttpServer::Impl : ServerCore {
  using ServerCore::ServerCore;
};

HttpServer::HttpServer(HttpOptions options, Api& api, CellState& state)
    : impl_(std::make_unique<Impl>(std::move(options), api, state)) {
  auto& s = *impl_;
  if (s.options.tls_cert.empty() != s.options.tls_key.empty()) {
    throw std::invalid_argument("--tls-cert and --tls-key go together (HTTPS needs both)");
  }
  if (s.options.tls_cert.empty()) return;
  // TLS 1.2 and 1.3 only, OpenSSL's default cipher suites.
  s.tls.emplace(asio::ssl::context::tls_server);
  s.tls->set_options(asio::ssl::context::default_workarounds | asio::ssl::context::no_sslv2 |
                     asio::ssl::context::no_sslv3 | asio::ssl::context::no_tlsv1 |
                     asio::ssl::context::no_tlsv1_1 | asio::ssl::context::single_dh_use);
  beast::error_code ec;
  s.tls->use_certificate_chain_file(s.options.tls_cert, ec);
  if (ec) {
    throw std::runtime_error(s.options.tls_cert +
                             ": cannot use it as the HTTPS certificate (a PEM certificate "
                             "chain, server's first): " +
                             ec.message());
  }
  s.tls->use_private_key_file(s.options.tls_key, asio::ssl::context::pem, ec);
  if (ec) {
    throw std::runtime_error(s.options.tls_key +
                             ": cannot use it as the HTTPS key (PEM, the certificate's own "
                             "key, readable by this user): " +
                             ec.message());
  }
}

bool HttpServer::tls() const noexcept { return impl_->tls.has_value(); }

HttpServer::~HttpServer() { stop(); }

void HttpServer::start() {
  auto& s = *impl_;
  beast::error_code ec;
  const auto address = asio::ip::make_address(s.options.address, ec);
  if (ec) {
    throw std::runtime_error("--http: '" + s.options.address + "' is not an IP address");
  }
  const tcp::endpoint ep(address, s.options.port);
  s.acceptor.open(ep.protocol(), ec);
  if (!ec) s.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) s.acceptor.bind(ep, ec);
  if (!ec) s.acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + s.options.address + ":" +
                             std::to_string(s.options.port) + ": " + ec.message());
  }
  s.port = s.acceptor.local_endpoint().port();
  s.accept();
  s.schedule_tick();
  s.thread = std::thread([this] {
    // A handler that throws must not end the server: log it and go on.
    while (true) {
      try {
        impl_->ioc.run();
        return;
      } catch (const std::exception& e) {
        spdlog::error("http: unexpected error in a handler: {}", e.what());
      }
    }
  });
}

void HttpServer::stop() noexcept {
  auto& s = *impl_;
  if (!s.thread.joinable()) return;
  asio::post(s.ioc, [&s] {
    s.stopping = true;
    beast::error_code ec;
    s.acceptor.close(ec);
    s.timer.cancel();
    s.accept_retry.cancel();
    s.hub.close_all();
  });
  // Give the close handlers a moment, then stop whatever is still pending
  // (keep-alive connections waiting for a next request).
  asio::post(s.ioc, [&s] { s.ioc.stop(); });
  s.thread.join();
}

std::uint16_t HttpServer::port() const noexcept { return impl_->port.load(); }

void HttpServer::publish(Event event) {
  asio::post(impl_->ioc, [this, e = std::move(event)] { impl_->hub.broadcast(e); });
}

std::string HttpServer::stats_json() const {
  JsonWriter w;
  const auto now = Clock::now();
  w.begin_object()
      .field("connections", impl_->connections)
      .field("requests", impl_->requests)
      .field("tls", impl_->tls.has_value())
      .field("tls_handshakes_failed", impl_->tls_handshakes_failed)
      .field("max_streams", impl_->options.max_streams)
      .field("stream_queue_events", impl_->options.stream_queue_events);
  impl_->hub.write_stats(w, now);
  w.end_object();
  return w.take();
}

}  // namespace smc::dashboard
