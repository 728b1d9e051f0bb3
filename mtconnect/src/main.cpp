// smc-mtconnect: the cell's mills as an MTConnect SHDR adapter (README.md).
//
// Two threads: the DDS thread takes the cell's samples and posts them to the
// I/O thread, which owns the SHDR model and the agents' connections. An
// agent that connects gets every current value, then every change; "* PING"
// is answered "* PONG <heartbeat ms>". An agent that falls behind by more
// than --max-queue lines is disconnected (it reconnects and gets the
// current values again).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <boost/asio.hpp>
#include <csignal>
#include <cstdio>
#include <deque>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "smc/common/clock.hpp"
#include "smc/common/log.hpp"
#include "smc/mtconnect/shdr_model.hpp"
#include "smc/transport/dispatcher.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/documents.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace asio = boost::asio;
using asio::ip::tcp;
namespace tr = smc::transport;
namespace mt = smc::mtconnect;

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

struct Options {
  std::string listen = "127.0.0.1:7878";
  std::uint32_t domain_id = 0;
  std::string partition;
  std::string dds_config;
  int heartbeat_ms = 10000;
  int sample_period_ms = 100;
  std::size_t max_queue = 20000;
};

class Server;

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, Server& server) : socket_(std::move(socket)), server_(server) {}
  void start(const std::vector<std::string>& snapshot);
  void send(const std::string& line);
  void close();
  std::string peer;

 private:
  void read();
  void write();
  tcp::socket socket_;
  Server& server_;
  asio::streambuf in_;
  std::deque<std::string> out_;
  bool writing_ = false;
  bool closed_ = false;
};

class Server {
 public:
  Server(asio::io_context& io, const Options& o)
      : io_(io), acceptor_(io), options_(o), model_(o.sample_period_ms * 1'000'000LL) {
    const auto colon = o.listen.rfind(':');
    if (colon == std::string::npos) {
      throw std::runtime_error("--listen " + o.listen + ": give HOST:PORT, e.g. 127.0.0.1:7878");
    }
    const tcp::endpoint ep(asio::ip::make_address(o.listen.substr(0, colon)),
                           static_cast<unsigned short>(std::stoi(o.listen.substr(colon + 1))));
    acceptor_.open(ep.protocol());
    acceptor_.set_option(tcp::acceptor::reuse_address(true));
    acceptor_.bind(ep);
    acceptor_.listen();
    accept();
  }
  unsigned short port() const { return acceptor_.local_endpoint().port(); }
  mt::ShdrModel& model() { return model_; }
  const Options& options() const { return options_; }
  void broadcast(const std::vector<std::string>& lines) {
    for (const auto& l : lines) {
      for (const auto& s : sessions_) s->send(l + "\n");
    }
  }
  // Later, on this thread: a session may close while broadcast() walks them.
  void drop(const std::shared_ptr<Session>& s) {
    asio::post(io_, [this, s] { sessions_.erase(s); });
  }

 private:
  void accept() {
    acceptor_.async_accept([this](boost::system::error_code ec, tcp::socket socket) {
      if (!ec) {
        auto s = std::make_shared<Session>(std::move(socket), *this);
        sessions_.insert(s);
        s->start(model_.snapshot(smc::unix_time_ns()));
      }
      if (acceptor_.is_open()) accept();
    });
  }
  asio::io_context& io_;
  tcp::acceptor acceptor_;
  Options options_;
  mt::ShdrModel model_;
  std::set<std::shared_ptr<Session>> sessions_;
};

void Session::start(const std::vector<std::string>& snapshot) {
  boost::system::error_code ec;
  const auto ep = socket_.remote_endpoint(ec);
  peer = ec ? "?" : ep.address().to_string() + ":" + std::to_string(ep.port());
  spdlog::info("agent {} connected: {} current values", peer, snapshot.size());
  for (const auto& l : snapshot) send(l + "\n");
  read();
}

void Session::send(const std::string& line) {
  if (closed_) return;
  if (out_.size() >= server_.options().max_queue) {
    spdlog::warn(
        "agent {} is {} lines behind: disconnected (it gets the current values when "
        "it reconnects)",
        peer, out_.size());
    close();
    return;
  }
  out_.push_back(line);
  if (!writing_) write();
}

void Session::write() {
  writing_ = true;
  auto self = shared_from_this();
  asio::async_write(socket_, asio::buffer(out_.front()),
                    [this, self](boost::system::error_code ec, std::size_t) {
                      if (ec) {
                        close();
                        return;
                      }
                      out_.pop_front();
                      if (out_.empty()) {
                        writing_ = false;
                      } else {
                        write();
                      }
                    });
}

void Session::read() {
  auto self = shared_from_this();
  asio::async_read_until(
      socket_, in_, '\n', [this, self](boost::system::error_code ec, std::size_t) {
        if (ec) {
          close();
          return;
        }
        std::istream is(&in_);
        std::string line;
        std::getline(is, line);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.rfind("* PING", 0) == 0) {
          send("* PONG " + std::to_string(server_.options().heartbeat_ms) + "\n");
        }
        read();
      });
}

void Session::close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ec;
  socket_.shutdown(tcp::socket::shutdown_both, ec);
  socket_.close(ec);
  spdlog::info("agent {} disconnected", peer);
  server_.drop(shared_from_this());
}

// Takes the cell's samples on its own thread and posts each to the I/O
// thread, where the model and the agents live.
void run_dds(const Options& o, asio::io_context& io, Server& server) {
  tr::ParticipantOptions po;
  po.domain_id = o.domain_id;
  po.partition = o.partition;
  po.config = o.dds_config;
  tr::Participant participant(po);
  tr::Topic<smc_data_ForceSummary> summary_topic(participant);
  tr::Topic<smc_data_SupervisorSituation> situation_topic(participant);
  tr::Topic<smc_data_EdgeStatus> status_topic(participant);
  tr::Topic<smc_data_ChatterEvent> chatter_topic(participant);
  tr::Topic<smc_data_JobProgress> progress_topic(participant);
  tr::Reader<smc_data_ForceSummary> summaries(summary_topic);
  tr::Reader<smc_data_SupervisorSituation> situations(situation_topic);
  tr::Reader<smc_data_EdgeStatus> statuses(status_topic);
  tr::Reader<smc_data_ChatterEvent> chatters(chatter_topic);
  tr::Reader<smc_data_JobProgress> progresses(progress_topic);
  smc::wire::DocumentSubscriber<smc::config::SupervisorConfig> configs(participant);
  smc::wire::DocumentSubscriber<smc::config::PartProgram> programs(participant);
  tr::Dispatcher dispatcher(participant);
  auto post = [&io, &server](auto f) {
    asio::post(io, [&server, f = std::move(f)] { server.broadcast(f(server.model())); });
  };
  auto serve = [&](auto& reader, auto handle) {
    dispatcher.on(reader, [&reader, handle, &post] {
      reader.take(
          [&](const auto& s, const tr::SampleInfo& i) {
            if (!i.valid_data) return;
            const std::int64_t t = i.source_timestamp_ns;
            post([s, t, handle](mt::ShdrModel& m) { return handle(m, s, t); });
          },
          64);
    });
  };
  serve(summaries, [](mt::ShdrModel& m, const smc_data_ForceSummary& s, std::int64_t t) {
    return m.on_summary(s, t);
  });
  serve(situations, [](mt::ShdrModel& m, const smc_data_SupervisorSituation& s, std::int64_t t) {
    return m.on_situation(s, t);
  });
  serve(chatters, [](mt::ShdrModel& m, const smc_data_ChatterEvent& s, std::int64_t t) {
    return m.on_chatter(s, t);
  });
  serve(progresses, [](mt::ShdrModel& m, const smc_data_JobProgress& s, std::int64_t t) {
    return m.on_progress(s, t);
  });
  dispatcher.on_instances(
      statuses,
      [&](const smc_data_EdgeStatus& s, const tr::SampleInfo& i) {
        const std::int64_t t = i.source_timestamp_ns;
        post([s, t](mt::ShdrModel& m) { return m.on_status(s, t); });
      },
      [&](const smc_data_EdgeStatus& s, tr::InstanceState) {
        const std::string id = smc::wire::get_string(s.machine_id);
        const std::int64_t t = smc::unix_time_ns();
        post([id, t](mt::ShdrModel& m) { return m.on_gone(id, t); });
      });
  auto reject = [](const tr::EnvelopeRejection& e) {
    spdlog::warn("rejected document: {}", e.message);
  };
  dispatcher.on(configs.reader(), [&] {
    configs.take(
        [&](const std::string& key, const smc::config::SupervisorConfig& c) {
          const std::int64_t t = smc::unix_time_ns();
          post([key, c, t](mt::ShdrModel& m) { return m.on_config(key, c, t); });
        },
        reject);
  });
  dispatcher.on(programs.reader(), [&] {
    programs.take(
        [&](const std::string& key, const smc::config::PartProgram& p) {
          const std::int64_t t = smc::unix_time_ns();
          post([key, p, t](mt::ShdrModel& m) { return m.on_program(key, p, t); });
        },
        reject);
  });
  while (!g_stop.load()) {
    try {
      dispatcher.run_once(std::chrono::milliseconds(200));
    } catch (const std::exception& e) {
      spdlog::error("dds: {}", e.what());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "smc-mtconnect: the cell's mills as an MTConnect adapter. Serves SHDR (the adapter\n"
      "protocol MTConnect agents read) on TCP: per mill availability, execution, program and\n"
      "pass, the supervisor in force, spindle speed, feedrate and override, F_Y, spindle power,\n"
      "and the chatter and edge-fault conditions. Point an agent's adapter at --listen, with\n"
      "the devices of 'smc-mtconnect devices' (mtconnect/README.md)."};
  Options o;
  smc::log::Options log_opts{.name = "smc-mtconnect"};
  app.add_option("--listen", o.listen, "HOST:PORT for agents (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--domain", o.domain_id, "DDS domain id")->capture_default_str();
  app.add_option("--partition", o.partition, "DDS partition (the cell's)");
  app.add_option("--dds-config", o.dds_config,
                 "Cyclone DDS XML or file://PATH (default: $CYCLONEDDS_URI, else loopback)");
  app.add_option("--heartbeat-ms", o.heartbeat_ms, "the heartbeat announced in * PONG")
      ->capture_default_str()
      ->check(CLI::Range(100, 600000));
  app.add_option("--sample-period-ms", o.sample_period_ms,
                 "send a mill's samples (speed, feed, F_Y, power) at most this often")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  app.add_option("--max-queue", o.max_queue,
                 "lines an agent may fall behind before it is disconnected")
      ->capture_default_str();
  app.add_option("--log-level", log_opts.level,
                 "trace|debug|info|warn|error|critical|off (default: $SMC_LOG_LEVEL or info)");
  std::string machines;
  auto* devices = app.add_subcommand(
      "devices", "Print the agent's device file (Devices.xml) for these mills and exit");
  devices->add_option("--machines", machines, "comma-separated machine ids, e.g. mill-1,mill-2")
      ->required();
  try {
    app.parse(argc, argv);
    if (*devices) {
      std::vector<std::string> ids;
      std::stringstream ss(machines);
      for (std::string id; std::getline(ss, id, ',');) {
        if (!id.empty()) ids.push_back(id);
      }
      std::fputs(mt::devices_xml(ids).c_str(), stdout);
      return 0;
    }
    smc::log::init(log_opts);
    // A sample a machine's writer sent about another machine (refused).
    smc::transport::set_refusal_handler(
        [](const std::string& what) { spdlog::warn("dds: {}", what); });
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    asio::io_context io;
    Server server(io, o);
    // The port on stdout first (tests and scripts read it), then the log.
    std::printf("listening on port %u\n", server.port());
    std::fflush(stdout);
    spdlog::info("SHDR adapter on {} (port {}), partition '{}'", o.listen, server.port(),
                 o.partition);
    auto guard = asio::make_work_guard(io);
    std::thread io_thread([&io] { io.run(); });
    run_dds(o, io, server);
    guard.reset();
    io.stop();
    io_thread.join();
    smc::log::shutdown();
    return 0;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "smc-mtconnect: error: %s\n", e.what());
    return 1;
  }
}
