// The one service loop: readers served in priority order on every wake-up,
// instances gone reported apart from samples, polled and periodic work,
// wake() from another thread; typed document topics with the schema from the
// Protobuf descriptor.

#include "smc/transport/dispatcher.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/documents.hpp"
#include "smc/wire/limits.hpp"
#include "smc/wire/topics.hpp"

using namespace smc::transport;
using smc::wire::get_string;
using smc::wire::set_string;
using namespace std::chrono_literals;

namespace {

// Runs the dispatcher until `done()` or the deadline; false on the deadline.
template <class Done>
bool run_until(Dispatcher& d, Done done, std::chrono::seconds deadline = 10s) {
  const auto end = std::chrono::steady_clock::now() + deadline;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    d.run_once(50ms);
  }
  return true;
}

}  // namespace

TEST(Dispatcher, ServesReadersInPriorityOrderEveryWakeUp) {
  Participant p({.partition = smc::test::unique_partition("disp-order")});
  Topic<smc_data_ForceSummary> summaries(p);
  Topic<smc_data_OperatorCommand> commands(p);
  Reader<smc_data_ForceSummary> summary_reader(summaries);
  Reader<smc_data_OperatorCommand> command_reader(commands);
  Writer<smc_data_ForceSummary> summary_writer(summaries);
  Writer<smc_data_OperatorCommand> command_writer(commands);
  ASSERT_TRUE(summary_writer.wait_for_readers(1, 5s));
  ASSERT_TRUE(command_writer.wait_for_readers(1, 5s));

  Dispatcher d(p);
  std::vector<std::string> calls;
  int summaries_taken = 0, commands_taken = 0;
  // Registered first, served last.
  d.on(summary_reader, [&] {
    calls.push_back("summary");
    summaries_taken += static_cast<int>(summary_reader.take([](auto&, auto&) {}));
  });
  d.on(
      command_reader,
      [&] {
        calls.push_back("command");
        commands_taken += static_cast<int>(command_reader.take([](auto&, auto&) {}));
      },
      Dispatcher::Priority::kFirst);
  int polled = 0;
  d.poll(
      [&] {
        calls.push_back("poll");
        ++polled;
      },
      Dispatcher::Priority::kLast);

  smc_data_ForceSummary s{};
  set_string(s.machine_id, "mill-1");
  summary_writer.write(s);
  smc_data_OperatorCommand c{};
  set_string(c.machine_id, "mill-1");
  command_writer.write(c);
  ASSERT_TRUE(run_until(d, [&] { return summaries_taken == 1 && commands_taken == 1; }));
  ASSERT_GE(calls.size(), 3u);
  EXPECT_EQ(calls[0], "command");
  EXPECT_EQ(calls[1], "summary");
  EXPECT_EQ(calls[2], "poll");
  EXPECT_GE(polled, 1);
}

TEST(Dispatcher, AnInstanceWhoseWriterIsGoneIsReportedApartFromItsSamples) {
  const std::string partition = smc::test::unique_partition("disp-gone");
  Participant p({.partition = partition});
  Topic<smc_data_EdgeStatus> topic(p);
  Reader<smc_data_EdgeStatus> reader(topic);
  Dispatcher d(p);
  std::vector<std::string> alive, gone;
  d.on_instances(
      reader,
      [&](const smc_data_EdgeStatus& s, const SampleInfo&) {
        alive.push_back(get_string(s.machine_id));
      },
      [&](const smc_data_EdgeStatus& key, InstanceState) {
        gone.push_back(get_string(key.machine_id));
      });
  {
    Participant edge({.partition = partition});
    Topic<smc_data_EdgeStatus> t(edge);
    Writer<smc_data_EdgeStatus> w(t, t.qos().with_lease(200ms));
    ASSERT_TRUE(w.wait_for_readers(1, 5s));
    smc_data_EdgeStatus st{};
    set_string(st.machine_id, "mill-9");
    w.write(st);
    ASSERT_TRUE(run_until(d, [&] { return !alive.empty(); }));
  }  // the edge's participant is deleted: its writer is gone
  ASSERT_TRUE(run_until(d, [&] { return !gone.empty(); }));
  EXPECT_EQ(alive, std::vector<std::string>{"mill-9"});
  EXPECT_EQ(gone, std::vector<std::string>{"mill-9"});
}

TEST(Dispatcher, PeriodicWorkRunsWhenDueAndWakeEndsAWaitEarly) {
  Participant p({.partition = smc::test::unique_partition("disp-wake")});
  Dispatcher d(p);
  int due = 0, later = 0;
  d.every(1ns, [&] { ++due; });
  d.every(1h, [&] { ++later; });
  d.run_once(1ms);
  d.run_once(1ms);
  EXPECT_EQ(due, 2);
  EXPECT_EQ(later, 0);

  Dispatcher quiet(p);
  std::thread waker([&] {
    std::this_thread::sleep_for(50ms);
    quiet.wake();
  });
  const auto t0 = std::chrono::steady_clock::now();
  quiet.run_once(60s);
  waker.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 30s);  // woken, not timed out
}

TEST(WireDocuments, SchemaFromTheDescriptorAndARoundTrip) {
  EXPECT_EQ(smc::wire::schema<smc::config::SupervisorConfig>().name, "smc.config.SupervisorConfig");
  EXPECT_EQ(smc::wire::schema<smc::config::JobStatus>().name, "smc.config.JobStatus");
  EXPECT_EQ(smc::wire::schema<smc::config::JobAssignment>().version,
            static_cast<uint32_t>(smc::config::SCHEMA_VERSION_CURRENT));

  Participant p({.partition = smc::test::unique_partition("disp-doc")});
  smc::wire::DocumentPublisher<smc::config::JobAssignment> out(p);
  smc::wire::DocumentSubscriber<smc::config::JobAssignment> in(p);
  ASSERT_TRUE(out.writer_for("mill-1").wait_for_readers(1, 5s));
  Dispatcher d(p);
  std::optional<smc::config::JobAssignment> got;
  d.on(in.reader(), [&] {
    in.take([&](const std::string&, const smc::config::JobAssignment& a) { got = a; },
            [](const EnvelopeRejection& e) { ADD_FAILURE() << e.message; });
  });
  smc::config::JobAssignment a;
  a.set_job_id("job-1");
  a.set_attempt(2);
  out.publish("mill-1", "job-1", a);
  ASSERT_TRUE(run_until(d, [&] { return got.has_value(); }));
  EXPECT_EQ(got->job_id(), "job-1");
  EXPECT_EQ(got->attempt(), 2u);
}

TEST(WireLimits, ReadOffTheGeneratedTypes) {
  EXPECT_EQ(smc::wire::kMachineIdMax, 31u);
  EXPECT_EQ(smc::wire::kJobIdMax, 63u);
  EXPECT_EQ(smc::wire::kDocumentKeyMax, 63u);
  EXPECT_EQ(smc::wire::kForceBatchMax, 128);
}
