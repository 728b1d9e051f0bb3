#include "smc/dashboard/dashboard.hpp"

#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <charconv>
#include <cstdio>
#include <stdexcept>

#include "api.hpp"
#include "assets.hpp"
#include "auth.hpp"
#include "cell_state.hpp"
#include "dds_bridge.hpp"
#include "http_server.hpp"
#include "job_history.hpp"

namespace smc::dashboard {

std::pair<std::string, std::uint16_t> parse_listen_address(std::string_view text) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 == text.size()) {
    throw std::invalid_argument("--http '" + std::string(text) + "': expected HOST:PORT");
  }
  std::string_view host = text.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  const std::string_view port_text = text.substr(colon + 1);
  unsigned port = 0;
  const auto r = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (r.ec != std::errc() || r.ptr != port_text.data() + port_text.size() || port > 65535) {
    throw std::invalid_argument("--http '" + std::string(text) + "': port must be 0-65535");
  }
  return {std::string(host), static_cast<std::uint16_t>(port)};
}

namespace {

HttpOptions http_options(const Options& o) {
  HttpOptions h;
  std::tie(h.address, h.port) = parse_listen_address(o.http);
  h.max_streams = o.max_streams;
  h.stream_queue_events = o.stream_queue_events;
  h.stream_send_buffer = o.stream_send_buffer;
  h.stall_timeout = o.stall_timeout;
  h.heartbeat = o.heartbeat;
  h.max_body = o.max_body;
  h.tls_cert = o.tls_cert;
  h.tls_key = o.tls_key;
  return h;
}

DdsOptions dds_options(const Options& o) {
  DdsOptions d;
  d.domain_id = o.domain_id;
  d.partition = o.partition;
  d.config = o.dds_config;
  return d;
}

Auth load_auth(const Options& o) {
  return o.token_file.empty() ? Auth() : Auth::from_file(o.token_file);
}

std::unique_ptr<JobHistory> open_history(const Options& o) {
  if (o.cell_db.empty()) return nullptr;
  return std::make_unique<JobHistory>(o.cell_db);
}

}  // namespace

struct Dashboard::Impl {
  explicit Impl(const Options& o)
      : options(o),
        auth(load_auth(o)),
        assets(o.web_root),
        history(open_history(o)),
        api(Api::Deps{state, auth, bridge_proxy, assets, [this] { return stats(); },
                      history.get()}),
        server(http_options(o), api, state),
        bridge(dds_options(o), state, server) {
    bridge_proxy.target = &bridge;
  }

  // The Api is built before the bridge exists; it reaches it through this.
  struct BridgeProxy final : CommandSink {
    void submit(CommandRequest request, Done done) override {
      target->submit(std::move(request), std::move(done));
    }
    DdsBridge* target = nullptr;
  };

  std::string stats() const {
    const auto st = state.counters();
    const auto br = bridge.counters();
    std::string s = server.stats_json();
    s.pop_back();  // extend the server's object
    s += ",\"dds_samples\":" + std::to_string(st.samples) +
         ",\"dds_ignored\":" + std::to_string(st.ignored) +
         ",\"documents_rejected\":" + std::to_string(br.documents_rejected) +
         ",\"commands_sent\":" + std::to_string(br.commands_sent) +
         ",\"commands_failed\":" + std::to_string(br.commands_failed) + "}";
    return s;
  }

  Options options;
  Auth auth;
  Assets assets;
  std::unique_ptr<JobHistory> history;  // null without --cell-db
  CellState state;
  BridgeProxy bridge_proxy;
  Api api;
  HttpServer server;
  DdsBridge bridge;
};

Dashboard::Dashboard(const Options& options) : impl_(std::make_unique<Impl>(options)) {}

Dashboard::~Dashboard() { stop(); }

void Dashboard::start() {
  impl_->server.start();
  impl_->bridge.start();
  spdlog::info("dashboard on {} (DDS domain {}, partition '{}'); {}", url(),
               impl_->options.domain_id, impl_->options.partition,
               impl_->auth.enabled()
                   ? std::to_string(impl_->auth.size()) + " operator token(s): commands enabled"
                   : std::string("no operator tokens: read-only"));
}

void Dashboard::stop() noexcept {
  impl_->bridge.stop();  // first: it publishes into the server
  impl_->server.stop();
}

std::uint16_t Dashboard::port() const noexcept { return impl_->server.port(); }

std::string Dashboard::url() const {
  std::string host = parse_listen_address(impl_->options.http).first;
  if (host.find(':') != std::string::npos) host = "[" + host + "]";
  return (impl_->server.tls() ? "https://" : "http://") + host + ":" + std::to_string(port()) + "/";
}

int run(const Options& options) {
  // Block the stop signals in every thread, then wait for one here.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  Dashboard dashboard(options);
  dashboard.start();
  std::printf("smc-dashboard: listening on %s\n", dashboard.url().c_str());
  std::fflush(stdout);
  int sig = 0;
  sigwait(&signals, &sig);
  spdlog::info("signal {}: stopping", sig);
  dashboard.stop();
  return 0;
}

std::string hash_token_line(std::string_view name, std::string_view token) {
  return Auth::hash_line(name, token);
}

}  // namespace smc::dashboard
