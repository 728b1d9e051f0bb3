#include "dds_bridge.hpp"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "cell_state.hpp"
#include "event.hpp"
#include "smc/common/clock.hpp"
#include "smc/transport/dispatcher.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/documents.hpp"
#include "smc/wire/topics.hpp"

namespace smc::dashboard {

namespace {

using namespace std::chrono_literals;
namespace tr = smc::transport;

// Samples taken per reader per wake-up, so that one busy topic cannot starve
// the others (or the command queue) for long.
constexpr std::size_t kTakeBatch = 256;

smc_data_OperatorAction wire_action(CommandAction a) {
  switch (a) {
    case CommandAction::kFeedHoldOn:
      return smc_data_OP_FEED_HOLD_ON;
    case CommandAction::kFeedHoldOff:
      return smc_data_OP_FEED_HOLD_OFF;
    case CommandAction::kChatterSignal:
      return smc_data_OP_CHATTER_SIGNAL;
  }
  return smc_data_OP_FEED_HOLD_ON;
}

std::uint64_t unix_now_ns() { return static_cast<std::uint64_t>(smc::unix_time_ns()); }

tr::ParticipantOptions participant_options(const DdsOptions& o) {
  tr::ParticipantOptions p;
  p.domain_id = o.domain_id;
  p.partition = o.partition;
  p.config = o.config;
  return p;
}

}  // namespace

struct DdsBridge::Impl {
  Impl(const DdsOptions& options, CellState& cell, EventSink& k)
      : state(cell),
        sink(k),
        participant(participant_options(options)),
        summary_topic(participant),
        batch_topic(participant),
        situation_topic(participant),
        status_topic(participant),
        chatter_topic(participant),
        progress_topic(participant),
        command_topic(participant),
        summaries(summary_topic),
        batches(batch_topic),
        situations(situation_topic),
        statuses(status_topic),
        chatters(chatter_topic),
        progresses(progress_topic),
        configs(participant),
        programs(participant),
        jobs(participant),
        catalogs(participant),
        dispatcher(participant),
        next_command_id(unix_now_ns() / 1000) {
    using P = tr::Dispatcher::Priority;
    // Operator commands first: they are written before any reader is served.
    dispatcher.poll([this] { write_pending_commands(); }, P::kFirst);
    serve(summaries, [this](const smc_data_ForceSummary& s, std::int64_t t) {
      publish(state.on_summary(s, t));
    });
    serve(batches,
          [this](const smc_data_ForceBatch& b, std::int64_t t) { publish(state.on_batch(b, t)); });
    serve(situations, [this](const smc_data_SupervisorSituation& s, std::int64_t t) {
      publish(state.on_situation(s, t));
    });
    dispatcher.on_instances(
        statuses,
        [this](const smc_data_EdgeStatus& s, const tr::SampleInfo&) {
          // The mill's command writer, made when the mill is first seen so
          // that it has matched the edge before the first command.
          try {
            (void)command_writer(wire::get_string(s.machine_id));
          } catch (const std::invalid_argument& e) {
            spdlog::warn("dds: {}", e.what());
          }
          publish(state.on_status(s));
        },
        // The key sample of an edge whose writer is gone.
        [this](const smc_data_EdgeStatus& s, tr::InstanceState) {
          publish(state.on_edge_gone(wire::get_string(s.machine_id)));
        });
    serve(chatters,
          [this](const smc_data_ChatterEvent& e, std::int64_t) { publish(state.on_chatter(e)); });
    serve(progresses,
          [this](const smc_data_JobProgress& p, std::int64_t) { publish(state.on_progress(p)); });
    auto on_reject = [this](const tr::EnvelopeRejection& err) {
      documents_rejected.fetch_add(1, std::memory_order_relaxed);
      spdlog::warn("dds: rejected document: {}", err.message);
    };
    dispatcher.on(configs.reader(), [this, on_reject] {
      configs.take([&](const std::string& key,
                       const config::SupervisorConfig& c) { publish(state.on_config(key, c)); },
                   on_reject);
    });
    dispatcher.on(programs.reader(), [this, on_reject] {
      programs.take([&](const std::string& key,
                        const config::PartProgram& p) { publish(state.on_program(key, p)); },
                    on_reject);
    });
    dispatcher.on(jobs.reader(), [this, on_reject] {
      jobs.take([&](const std::string& key,
                    const config::JobStatus& j) { publish(state.on_job(key, j)); },
                on_reject);
    });
    dispatcher.on(catalogs.reader(), [this, on_reject] {
      catalogs.take(
          [&](const std::string&, const config::CatalogView& v) { publish(state.on_catalog(v)); },
          on_reject);
    });
  }

  // A data-plane reader: valid samples, at most kTakeBatch per wake-up so
  // one busy topic cannot starve the others.
  template <class T, class F>
  void serve(tr::Reader<T>& reader, F on_sample) {
    dispatcher.on(reader, [&reader, on_sample] {
      reader.take(
          [&](const T& s, const tr::SampleInfo& i) {
            if (i.valid_data) on_sample(s, i.source_timestamp_ns);
          },
          kTakeBatch);
    });
  }

  void publish(std::vector<Event> events) {
    for (auto& e : events) sink.publish(std::move(e));
  }

  void run() {
    while (!stopping.load(std::memory_order_acquire)) {
      try {
        dispatcher.run_once(500ms);
      } catch (const std::exception& e) {
        // A failing DDS call must not end the dashboard; report and go on.
        spdlog::error("dds: {}", e.what());
        std::this_thread::sleep_for(100ms);
      }
    }
    fail_pending_commands("the dashboard is stopping");
  }

  void write_pending_commands() {
    std::deque<std::pair<CommandRequest, Done>> batch;
    {
      std::lock_guard lock(mu);
      batch.swap(pending);
    }
    for (auto& [req, done] : batch) {
      CommandRecord rec;
      rec.request = std::move(req);
      rec.command_id = ++next_command_id;
      rec.issued_unix_ns = unix_now_ns();
      smc_data_OperatorCommand cmd{};
      wire::set_string(cmd.machine_id, rec.request.machine_id);
      wire::set_string(cmd.operator_name, rec.request.operator_name);
      cmd.command_id = rec.command_id;
      cmd.issued_unix_ns = rec.issued_unix_ns;
      cmd.action = static_cast<std::int32_t>(wire_action(rec.request.action));
      try {
        auto& writer = command_writer(rec.request.machine_id);
        // Commands are volatile: one written while no edge of the mill
        // reads them is lost, so say so rather than report it sent.
        if (writer.publication_matched().current_count == 0) {
          throw std::runtime_error("no edge of " + rec.request.machine_id +
                                   " is reading operator commands (not running, or not yet "
                                   "matched): not delivered");
        }
        writer.write(cmd);
        rec.sent = true;
        commands_sent.fetch_add(1, std::memory_order_relaxed);
        spdlog::info("operator command {} sent: {} on {} by operator '{}' from {}", rec.command_id,
                     to_string(rec.request.action), rec.request.machine_id,
                     rec.request.operator_name, rec.request.remote);
      } catch (const std::exception& e) {
        rec.error = e.what();
        commands_failed.fetch_add(1, std::memory_order_relaxed);
        spdlog::error("operator command {} NOT sent: {} on {} by operator '{}' from {}: {}",
                      rec.command_id, to_string(rec.request.action), rec.request.machine_id,
                      rec.request.operator_name, rec.request.remote, rec.error);
      }
      publish(state.on_command(rec));
      if (done) done(rec);
    }
  }

  // Commands for a mill go into its partition, where its edge reads them
  // (tr::ParticipantOptions::machine). Throws std::invalid_argument for a
  // machine id that cannot name a partition.
  tr::Writer<smc_data_OperatorCommand>& command_writer(const std::string& machine) {
    auto it = commands.find(machine);
    if (it == commands.end()) {
      it = commands.emplace(machine, tr::Writer<smc_data_OperatorCommand>(command_topic, machine))
               .first;
    }
    return it->second;
  }

  void fail_pending_commands(const std::string& why) {
    std::deque<std::pair<CommandRequest, Done>> batch;
    {
      std::lock_guard lock(mu);
      batch.swap(pending);
    }
    for (auto& [req, done] : batch) {
      CommandRecord rec;
      rec.request = std::move(req);
      rec.error = why;
      if (done) done(rec);
    }
  }

  CellState& state;
  EventSink& sink;
  tr::Participant participant;
  tr::Topic<smc_data_ForceSummary> summary_topic;
  tr::Topic<smc_data_ForceBatch> batch_topic;
  tr::Topic<smc_data_SupervisorSituation> situation_topic;
  tr::Topic<smc_data_EdgeStatus> status_topic;
  tr::Topic<smc_data_ChatterEvent> chatter_topic;
  tr::Topic<smc_data_JobProgress> progress_topic;
  tr::Topic<smc_data_OperatorCommand> command_topic;
  tr::Reader<smc_data_ForceSummary> summaries;
  tr::Reader<smc_data_ForceBatch> batches;
  tr::Reader<smc_data_SupervisorSituation> situations;
  tr::Reader<smc_data_EdgeStatus> statuses;
  tr::Reader<smc_data_ChatterEvent> chatters;
  tr::Reader<smc_data_JobProgress> progresses;
  wire::DocumentSubscriber<config::SupervisorConfig> configs;
  wire::DocumentSubscriber<config::PartProgram> programs;
  wire::DocumentSubscriber<config::JobStatus> jobs;
  wire::DocumentSubscriber<config::CatalogView> catalogs;
  // One per mill, made on first use; only the DDS thread touches it.
  std::map<std::string, tr::Writer<smc_data_OperatorCommand>> commands;
  tr::Dispatcher dispatcher;

  std::thread thread;
  std::atomic<bool> stopping{false};
  mutable std::mutex mu;  // guards `pending`
  std::deque<std::pair<CommandRequest, Done>> pending;
  std::uint64_t next_command_id;
  std::atomic<std::uint64_t> commands_sent{0};
  std::atomic<std::uint64_t> commands_failed{0};
  std::atomic<std::uint64_t> documents_rejected{0};
};

DdsBridge::DdsBridge(const DdsOptions& options, CellState& state, EventSink& sink)
    : impl_(std::make_unique<Impl>(options, state, sink)) {}

DdsBridge::~DdsBridge() { stop(); }

void DdsBridge::start() {
  if (impl_->thread.joinable()) return;
  impl_->thread = std::thread([this] { impl_->run(); });
}

void DdsBridge::stop() noexcept {
  if (!impl_->thread.joinable()) return;
  impl_->stopping.store(true, std::memory_order_release);
  try {
    impl_->dispatcher.wake();
  } catch (...) {  // the wait times out within 500 ms anyway
  }
  impl_->thread.join();
}

void DdsBridge::submit(CommandRequest request, Done done) {
  bool queued = false;
  {
    std::lock_guard lock(impl_->mu);
    if (!impl_->stopping.load(std::memory_order_acquire) && impl_->thread.joinable()) {
      impl_->pending.emplace_back(std::move(request), std::move(done));
      queued = true;
    }
  }
  if (queued) {
    impl_->dispatcher.wake();
    return;
  }
  CommandRecord rec;
  rec.request = std::move(request);
  rec.error = "the dashboard's DDS side is not running";
  if (done) done(rec);
}

DdsBridge::Counters DdsBridge::counters() const {
  return Counters{impl_->commands_sent.load(std::memory_order_relaxed),
                  impl_->commands_failed.load(std::memory_order_relaxed),
                  impl_->documents_rejected.load(std::memory_order_relaxed)};
}

}  // namespace smc::dashboard
