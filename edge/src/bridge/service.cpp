#include <spdlog/spdlog.h>

#include "bridge.hpp"

namespace smc::edge {

using namespace std::chrono_literals;

EdgeService::Impl::Impl(ServiceOptions o)
    : opt(std::move(o)),
      // The mill's own partition: it publishes and reads nothing else.
      participant(
          {.domain_id = opt.domain_id, .partition = opt.partition, .machine = opt.machine_id}),
      config_reader(participant),
      job_reader(participant),
      command_topic(participant),
      command_reader(command_topic),
      summary_topic(participant),
      summary_writer(summary_topic),
      batch_topic(participant),
      batch_writer(batch_topic),
      chatter_topic(participant),
      chatter_writer(chatter_topic),
      situation_topic(participant),
      situation_writer(situation_topic),
      status_topic(participant),
      status_writer(status_topic, status_topic.qos().with_lease(opt.lease)),
      progress_topic(participant),
      progress_writer(progress_topic),
      program_writer(participant),
      dispatcher(participant),
      intake(std::make_unique<ConfigIntake>(
          [this](const smc::config::SupervisorConfig& cfg) { return check(cfg); },
          [this] { dispatcher.wake(); })) {
  load_journal();
  using P = tr::Dispatcher::Priority;
  // Operator commands first: served before any other reader on every wake-up.
  dispatcher.on(
      command_reader, [this] { take_commands(); }, P::kFirst);
  dispatcher.on(config_reader.reader(), [this] { take_configs(); });
  dispatcher.poll([this] { apply_checked_configs(); });
  dispatcher.on(job_reader.reader(), [this] { take_jobs(); });
  // The loop's rings and the job's life, on every wake-up (at least every 2 ms).
  dispatcher.poll([this] { supervise_job(); }, P::kLast);
}

void EdgeService::Impl::supervise_job() {
  drain();
  if (job) {
    if (job->done || !job_running()) {
      finish_job();
    } else if (std::chrono::steady_clock::now() - job->last_progress > 1s) {
      publish_progress(smc_data_JOB_RUNNING, "running");
    }
  }
  if (std::chrono::steady_clock::now() - last_status > 1s) publish_status();
}

int EdgeService::Impl::run(const std::atomic<bool>& stop) {
  publish_status();
  // Every 2 ms at least: the loop's rings are drained and its situation
  // published within 2 ms of the loop's change (about 0.5 % of a core).
  while (!stop.load()) dispatcher.run_once(2ms);
  if (job) {
    stop_loop();
    drain();
    publish_progress(smc_data_JOB_INTERRUPTED, "edge stopped");
    job.reset();
  }
  return 0;
}

EdgeService::EdgeService(ServiceOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}
EdgeService::~EdgeService() = default;
int EdgeService::run(const std::atomic<bool>& stop) { return impl_->run(stop); }

}  // namespace smc::edge
