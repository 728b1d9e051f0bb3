#pragma once
// The dashboard's side of DDS, on one thread it owns: a waitset over a reader
// of every live topic (data plane and the documents smc_config, smc_program,
// smc_job_status); each sample is recorded in CellState and its events go to
// the EventSink. Operator commands from HTTP handlers are queued, written on
// smc_operator_command by this thread, and completed back to the caller.
// HTTP handler threads never call DDS.

#include <cstdint>
#include <memory>
#include <string>

#include "command.hpp"

namespace smc::dashboard {

class CellState;
class EventSink;

struct DdsOptions {
  std::uint32_t domain_id = 0;
  std::string partition;  // empty: the default partition
  std::string config;     // Cyclone DDS XML or file://; empty: transport default (loopback)
};

class DdsBridge final : public CommandSink {
 public:
  // Creates the participant and every reader and writer (throws DdsError).
  DdsBridge(const DdsOptions& options, CellState& state, EventSink& sink);
  ~DdsBridge() override;  // stops the thread
  DdsBridge(const DdsBridge&) = delete;
  DdsBridge& operator=(const DdsBridge&) = delete;

  void start();
  void stop() noexcept;

  // Any thread. `done` runs on the DDS thread once the command is written
  // (or failed); it must not block.
  void submit(CommandRequest request, Done done) override;

  struct Counters {
    std::uint64_t commands_sent = 0;
    std::uint64_t commands_failed = 0;
    std::uint64_t documents_rejected = 0;
  };
  Counters counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::dashboard
