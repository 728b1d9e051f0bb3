#pragma once
// A dashboard started in this process on a free port and a DDS partition of
// its own, and a DDS participant in the same partition playing the edges
// and the cell (writers of every live topic, a reader of operator commands).

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "http_client.hpp"
#include "smc/dashboard/dashboard.hpp"
#include "smc/transport/document.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::test {

inline constexpr const char* kAliceToken = "alice-token-0123456789abcdef";
inline constexpr const char* kBobToken = "bob-token-fedcba9876543210";

// Waits for `cond` (polled) until the deadline.
template <class F>
bool eventually(F&& cond, std::chrono::milliseconds timeout = std::chrono::milliseconds(10000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!cond()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline transport::Schema schema_of(const google::protobuf::Message& m) {
  return transport::Schema{m.GetDescriptor()->full_name(), config::SCHEMA_VERSION_CURRENT};
}

struct CellSide {
  explicit CellSide(const std::string& partition)
      : participant(transport::ParticipantOptions{0, {}, partition}),
        summary_topic(participant),
        batch_topic(participant),
        situation_topic(participant),
        status_topic(participant),
        command_topic(participant),
        config_topic(participant, wire::kConfigTopic),
        job_topic(participant, wire::kJobStatusTopic),
        summaries(summary_topic),
        batches(batch_topic),
        situations(situation_topic),
        statuses(status_topic),
        commands(command_topic),
        configs(config_topic, schema_of(config::SupervisorConfig::default_instance())),
        jobs(job_topic, schema_of(config::JobStatus::default_instance())) {}

  // As an edge reports it: its state and the configuration it has in force.
  void status(const std::string& mill, smc_data_EdgeState state = smc_data_EDGE_RUNNING,
              const std::string& config_in_force = "cfg-1") {
    smc_data_EdgeStatus s{};
    wire::set_string(s.machine_id, mill);
    s.state = state;
    wire::set_string(s.config_id, config_in_force);
    wire::set_string(s.message, "test");
    statuses.write(s);
  }
  void summary(const std::string& mill, uint32_t revolution, float f_y = 180.f) {
    smc_data_ForceSummary s{};
    wire::set_string(s.machine_id, mill);
    s.machine_time_ns = 1000000000ULL + uint64_t{revolution} * 40000000ULL;
    s.revolution = revolution;
    s.f_y_peak_n = f_y;
    s.f_ref_n = 190.f;
    s.spindle_power_w = 4.f * f_y;
    s.pass_count = 1;
    s.in_contact = true;
    summaries.write(s);
  }
  void situation(const std::string& mill, uint64_t steps, uint32_t modules, uint32_t seq) {
    smc_data_SupervisorSituation s{};
    wire::set_string(s.machine_id, mill);
    s.machine_time_ns = 2000000000ULL + seq;
    s.sequence_number = seq;
    s.active_steps = steps;
    s.modules_active = modules;
    wire::set_string(s.config_id, "cfg-1");
    situations.write(s);
  }

  transport::Participant participant;
  transport::Topic<smc_data_ForceSummary> summary_topic;
  transport::Topic<smc_data_ForceBatch> batch_topic;
  transport::Topic<smc_data_SupervisorSituation> situation_topic;
  transport::Topic<smc_data_EdgeStatus> status_topic;
  transport::Topic<smc_data_OperatorCommand> command_topic;
  transport::Topic<smc_data_Envelope> config_topic;
  transport::Topic<smc_data_Envelope> job_topic;
  transport::Writer<smc_data_ForceSummary> summaries;
  transport::Writer<smc_data_ForceBatch> batches;
  transport::Writer<smc_data_SupervisorSituation> situations;
  transport::Writer<smc_data_EdgeStatus> statuses;
  transport::Reader<smc_data_OperatorCommand> commands;
  transport::DocumentWriter configs;
  transport::DocumentWriter jobs;
};

class DashboardFixture {
 public:
  // `tokens`: write a token file (alice and bob) and enable commands.
  explicit DashboardFixture(bool tokens = true, dashboard::Options extra = {})
      : partition_(unique_partition("dashboard")) {
    dashboard::Options o = extra;
    o.http = "127.0.0.1:0";
    o.partition = partition_;
    if (tokens) {
      token_file_ = (std::filesystem::temp_directory_path() /
                     ("smc-dashboard-tokens-" + std::to_string(::getpid()) + "-" +
                      std::to_string(std::chrono::steady_clock::now().time_since_epoch().count())))
                        .string();
      std::ofstream(token_file_) << "# test operators (their tokens' SHA-256)\n"
                                 << dashboard::hash_token_line("alice", kAliceToken) << "\n"
                                 << dashboard::hash_token_line("bob", kBobToken) << "\n";
      std::filesystem::permissions(
          token_file_, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
      o.token_file = token_file_;
    }
    dashboard_ = std::make_unique<dashboard::Dashboard>(o);
    dashboard_->start();
    cell_ = std::make_unique<CellSide>(partition_);
  }
  ~DashboardFixture() {
    cell_.reset();
    dashboard_.reset();
    if (!token_file_.empty()) std::filesystem::remove(token_file_);
  }

  uint16_t port() const { return dashboard_->port(); }
  // The edges and the cell go away (their writers with them).
  void drop_cell() { cell_.reset(); }
  CellSide& cell() { return *cell_; }
  const std::string& partition() const { return partition_; }

  // Publishes an EdgeStatus for `mill` until the dashboard lists it.
  bool make_mill(const std::string& mill) {
    return eventually([&] {
      cell_->status(mill);
      return http(port(), "GET", "/api/mills/" + mill).status == 200;
    });
  }

 private:
  std::string partition_;
  std::string token_file_;
  std::unique_ptr<dashboard::Dashboard> dashboard_;
  std::unique_ptr<CellSide> cell_;
};

}  // namespace smc::test
