// Transport: every wire type round-trips between two processes; late joiners
// get the last configuration per key; bad envelopes are rejected by name;
// the error path names the failing call.

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "smc/transport/document.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/error.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/names.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

using namespace smc::transport;
using smc::wire::get_string;
using smc::wire::set_string;
using namespace std::chrono_literals;

namespace {

uint32_t crc32_of(const uint8_t* data, size_t size) {
  return static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), data, static_cast<uInt>(size)));
}

// ---- one distinctive sample per type, and a field-by-field comparison ----

void fill(smc_data_ForceSummary& s) {
  set_string(s.machine_id, "mill-7");
  s.machine_time_ns = 123456789012345ULL;
  s.revolution = 4242;
  s.pass_index = 1;
  s.pass_count = 2;
  s.f_y_peak_n = 317.25f;
  s.f_ref_n = 300.5f;
  s.feedrate_mm_s = 9.75f;
  s.feed_per_tooth_mm = 0.0975f;
  s.depth_mm = 1.0f;
  s.spindle_rpm = 1500.f;
  s.spindle_power_w = 701.f;
  s.in_contact = true;
  s.chatter = false;
}
void expect_same(const smc_data_ForceSummary& a, const smc_data_ForceSummary& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.machine_time_ns, b.machine_time_ns);
  EXPECT_EQ(a.revolution, b.revolution);
  EXPECT_EQ(a.pass_index, b.pass_index);
  EXPECT_EQ(a.pass_count, b.pass_count);
  EXPECT_EQ(a.f_y_peak_n, b.f_y_peak_n);
  EXPECT_EQ(a.f_ref_n, b.f_ref_n);
  EXPECT_EQ(a.feedrate_mm_s, b.feedrate_mm_s);
  EXPECT_EQ(a.feed_per_tooth_mm, b.feed_per_tooth_mm);
  EXPECT_EQ(a.depth_mm, b.depth_mm);
  EXPECT_EQ(a.spindle_rpm, b.spindle_rpm);
  EXPECT_EQ(a.spindle_power_w, b.spindle_power_w);
  EXPECT_EQ(a.in_contact, b.in_contact);
  EXPECT_EQ(a.chatter, b.chatter);
}

void fill(smc_data_ForceBatch& s) {
  set_string(s.machine_id, "mill-7");
  s.first_sample_time_ns = 99;
  s.sample_period_ns = 500000;
  s.decimation = 1;
  s.count = 80;
  for (int i = 0; i < 128; ++i) {
    s.f_y_n[i] = static_cast<float>(i) * 1.5f;
    s.f_z_n[i] = -static_cast<float>(i);
  }
}
void expect_same(const smc_data_ForceBatch& a, const smc_data_ForceBatch& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.first_sample_time_ns, b.first_sample_time_ns);
  EXPECT_EQ(a.sample_period_ns, b.sample_period_ns);
  EXPECT_EQ(a.decimation, b.decimation);
  EXPECT_EQ(a.count, b.count);
  EXPECT_EQ(0, std::memcmp(a.f_y_n, b.f_y_n, sizeof a.f_y_n));
  EXPECT_EQ(0, std::memcmp(a.f_z_n, b.f_z_n, sizeof a.f_z_n));
}

void fill(smc_data_ChatterEvent& s) {
  set_string(s.machine_id, "mill-7");
  s.event_id = 17;
  s.machine_time_ns = 5555;
  s.source = smc_data_CHATTER_AUTOMATIC;
  s.frequency_hz = 612.5f;
  s.energy_ratio = 3.25f;
  s.pass_index = 0;
  s.new_pass_count = 2;
  set_string(s.job_id, "job-000042");
}
void expect_same(const smc_data_ChatterEvent& a, const smc_data_ChatterEvent& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.event_id, b.event_id);
  EXPECT_EQ(a.machine_time_ns, b.machine_time_ns);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.frequency_hz, b.frequency_hz);
  EXPECT_EQ(a.energy_ratio, b.energy_ratio);
  EXPECT_EQ(a.pass_index, b.pass_index);
  EXPECT_EQ(a.new_pass_count, b.new_pass_count);
  EXPECT_EQ(get_string(a.job_id), get_string(b.job_id));
}

void fill(smc_data_SupervisorSituation& s) {
  set_string(s.machine_id, "mill-7");
  s.machine_time_ns = 77;
  s.sequence_number = 9;
  s.active_steps = 0x10;
  s.modules_active = 0xA0B;
  s.inputs = 0x3;
  set_string(s.config_id, "cfg-smc2-1");
}
void expect_same(const smc_data_SupervisorSituation& a, const smc_data_SupervisorSituation& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.machine_time_ns, b.machine_time_ns);
  EXPECT_EQ(a.sequence_number, b.sequence_number);
  EXPECT_EQ(a.active_steps, b.active_steps);
  EXPECT_EQ(a.modules_active, b.modules_active);
  EXPECT_EQ(a.inputs, b.inputs);
  EXPECT_EQ(get_string(a.config_id), get_string(b.config_id));
}

void fill(smc_data_EdgeStatus& s) {
  set_string(s.machine_id, "mill-7");
  s.machine_time_ns = 1;
  s.state = smc_data_EDGE_FEED_HOLD;
  set_string(s.config_id, "cfg");
  set_string(s.job_id, "job");
  s.loop_overruns = 3;
  s.loop_latency_p99_us = 41;
  set_string(s.message, "NaN force sample on F_y");
}
void expect_same(const smc_data_EdgeStatus& a, const smc_data_EdgeStatus& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.machine_time_ns, b.machine_time_ns);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(get_string(a.config_id), get_string(b.config_id));
  EXPECT_EQ(get_string(a.job_id), get_string(b.job_id));
  EXPECT_EQ(a.loop_overruns, b.loop_overruns);
  EXPECT_EQ(a.loop_latency_p99_us, b.loop_latency_p99_us);
  EXPECT_EQ(get_string(a.message), get_string(b.message));
}

void fill(smc_data_JobProgress& s) {
  set_string(s.machine_id, "mill-7");
  set_string(s.job_id, "job-1");
  s.machine_time_ns = 8;
  s.sequence_number = 4;
  s.phase = smc_data_JOB_RUNNING;
  s.pass_index = 1;
  s.pass_count = 2;
  s.depth_removed_mm = 1.0f;
  s.fraction_done = 0.625f;
  s.chatter_events = 1;
  s.peak_force_n = 680.f;
  set_string(s.message, "pass 2 of 2");
  s.program_rewrites = 1;
  s.spindle_speed_changes = 3;
}
void expect_same(const smc_data_JobProgress& a, const smc_data_JobProgress& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(get_string(a.job_id), get_string(b.job_id));
  EXPECT_EQ(a.machine_time_ns, b.machine_time_ns);
  EXPECT_EQ(a.sequence_number, b.sequence_number);
  EXPECT_EQ(a.phase, b.phase);
  EXPECT_EQ(a.pass_index, b.pass_index);
  EXPECT_EQ(a.pass_count, b.pass_count);
  EXPECT_EQ(a.depth_removed_mm, b.depth_removed_mm);
  EXPECT_EQ(a.fraction_done, b.fraction_done);
  EXPECT_EQ(a.chatter_events, b.chatter_events);
  EXPECT_EQ(a.peak_force_n, b.peak_force_n);
  EXPECT_EQ(get_string(a.message), get_string(b.message));
  EXPECT_EQ(a.program_rewrites, b.program_rewrites);
  EXPECT_EQ(a.spindle_speed_changes, b.spindle_speed_changes);
}

void fill(smc_data_OperatorCommand& s) {
  set_string(s.machine_id, "mill-7");
  s.command_id = 31;
  s.issued_unix_ns = 1700000000000000000ULL;
  s.action = static_cast<int32_t>(smc_data_OP_CHATTER_SIGNAL);
  set_string(s.operator_name, "alice");
}
void expect_same(const smc_data_OperatorCommand& a, const smc_data_OperatorCommand& b) {
  EXPECT_EQ(get_string(a.machine_id), get_string(b.machine_id));
  EXPECT_EQ(a.command_id, b.command_id);
  EXPECT_EQ(a.issued_unix_ns, b.issued_unix_ns);
  EXPECT_EQ(a.action, b.action);
  EXPECT_EQ(get_string(a.operator_name), get_string(b.operator_name));
}

// A fixture with the echo process and request/reply participants.
class RoundTrip : public ::testing::Test {
 protected:
  void SetUp() override {
    partition_ = smc::test::unique_partition("rt");
    echo_.emplace(std::vector<std::string>{smc::test::bin_path("smc-transport-echo"), "--partition",
                                           partition_, "--idle-s", "60"});
    ASSERT_TRUE(echo_->wait_for_line("ready"));
    req_.emplace(ParticipantOptions{.partition = partition_ + ".req"});
    rep_.emplace(ParticipantOptions{.partition = partition_ + ".rep"});
  }

  // Writes `sample` to the echo process and returns what comes back.
  template <class T>
  void round_trip(const T& sample, const std::function<void(const T&)>& check) {
    Topic<T> out_topic(*req_);
    Topic<T> in_topic(*rep_);
    Writer<T> w(out_topic);
    Reader<T> r(in_topic);
    ASSERT_TRUE(w.wait_for_readers(1, 10s)) << "echo reader not matched";
    ASSERT_TRUE(r.wait_for_writers(1, 10s)) << "echo writer not matched";
    WaitSet ws(*rep_);
    ws.attach(r, 1);
    w.write(sample);
    std::vector<int64_t> fired;
    bool got = false;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!got && std::chrono::steady_clock::now() < deadline) {
      ws.wait(500ms, fired);
      r.take([&](const T& s, const SampleInfo& info) {
        if (info.valid_data && !got) {
          got = true;
          check(s);
        }
      });
      // Best-effort topics may drop the very first sample before the
      // echo's reply path is fully matched: send again.
      if (!got) w.write(sample);
    }
    EXPECT_TRUE(got) << "no reply from the echo process";
  }

  std::string partition_;
  std::optional<smc::test::ChildProcess> echo_;
  std::optional<Participant> req_;
  std::optional<Participant> rep_;
};

}  // namespace

#define SMC_ROUND_TRIP_TEST(T)                                              \
  TEST_F(RoundTrip, T) {                                                    \
    T sample{};                                                             \
    fill(sample);                                                           \
    round_trip<T>(sample, [&](const T& got) { expect_same(sample, got); }); \
  }

SMC_ROUND_TRIP_TEST(smc_data_ForceSummary)
SMC_ROUND_TRIP_TEST(smc_data_ForceBatch)
SMC_ROUND_TRIP_TEST(smc_data_ChatterEvent)
SMC_ROUND_TRIP_TEST(smc_data_SupervisorSituation)
SMC_ROUND_TRIP_TEST(smc_data_EdgeStatus)
SMC_ROUND_TRIP_TEST(smc_data_JobProgress)
SMC_ROUND_TRIP_TEST(smc_data_OperatorCommand)

TEST(WireNames, EnumsAreNamedAsTheIdlSpellsThemAndStrayValuesAsUnknown) {
  using namespace smc::wire;
  EXPECT_STREQ(edge_state_name(smc_data_EDGE_FEED_HOLD), "EDGE_FEED_HOLD");
  EXPECT_STREQ(edge_state_name(smc_data_EDGE_FAULT), "EDGE_FAULT");
  EXPECT_STREQ(job_phase_name(smc_data_JOB_INTERRUPTED), "JOB_INTERRUPTED");
  EXPECT_STREQ(operator_action_name(smc_data_OP_CHATTER_SIGNAL), "OP_CHATTER_SIGNAL");
  EXPECT_STREQ(edge_state_name(99), "EDGE_UNKNOWN");
  EXPECT_STREQ(job_phase_name(-1), "JOB_UNKNOWN");
  EXPECT_STREQ(operator_action_name(7), "OP_UNKNOWN");
}

TEST_F(RoundTrip, EnvelopeCarriesProtobufDocument) {
  smc::config::SupervisorConfig cfg;
  cfg.set_config_id("cfg-42");
  cfg.set_variant(smc::config::SMC_II);
  cfg.set_grafcet_text("grafcet smc2\n");
  cfg.mutable_machine()->set_max_spindle_power_w(745.7);
  const Schema schema{"smc.config.SupervisorConfig", 1};
  smc_data_Envelope env;
  encode_envelope(cfg, schema, "mill-7", cfg.config_id(), 5, env);
  round_trip<smc_data_Envelope>(env, [&](const smc_data_Envelope& got) {
    EXPECT_EQ(get_string(got.key), "mill-7");
    EXPECT_EQ(got.sequence_number, 5u);
    smc::config::SupervisorConfig back;
    auto err = decode_envelope(got, schema, back);
    ASSERT_FALSE(err.has_value()) << err->message;
    EXPECT_EQ(back.SerializeAsString(), cfg.SerializeAsString());
  });
  free_envelope(env);
}

// ---- transient-local: a late reader gets the last document per key only ----

TEST(Configuration, LateReaderGetsLastDocumentPerKeyOnly) {
  const std::string partition = smc::test::unique_partition("late");
  smc::test::ChildProcess publisher({smc::test::bin_path("smc-transport-echo"), "--partition",
                                     partition, "--publish-configs", "3", "--idle-s", "30"});
  ASSERT_TRUE(publisher.wait_for_line("published"));

  // The reader joins after all six documents were written.
  Participant p({.partition = partition});
  Topic<smc_data_Envelope> topic(p, smc::wire::kConfigTopic);
  DocumentReader<smc::config::SupervisorConfig> reader(topic, {"smc.config.SupervisorConfig", 1});
  ASSERT_TRUE(reader.reader().wait_for_writers(1, 10s));
  std::vector<std::string> received;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (received.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    reader.take([&](const std::string&,
                    const smc::config::SupervisorConfig& c) { received.push_back(c.config_id()); },
                [&](const EnvelopeRejection& e) { ADD_FAILURE() << e.message; });
    std::this_thread::sleep_for(10ms);
  }
  // Give any (wrong) extra historical samples a moment to show up too.
  std::this_thread::sleep_for(200ms);
  reader.take([&](const std::string&,
                  const smc::config::SupervisorConfig& c) { received.push_back(c.config_id()); },
              [&](const EnvelopeRejection& e) { ADD_FAILURE() << e.message; });
  std::sort(received.begin(), received.end());
  EXPECT_EQ(received, (std::vector<std::string>{"m1-v3", "m2-v3"}));
  ASSERT_NE(reader.current("m1"), nullptr);
  EXPECT_EQ(reader.current("m1")->config_id(), "m1-v3");
}

// ---- bad envelopes are rejected by name; the accepted one stays in force ----

class BadEnvelope : public ::testing::Test {
 protected:
  void SetUp() override {
    partition_ = smc::test::unique_partition("bad");
    p_.emplace(ParticipantOptions{.partition = partition_});
    topic_.emplace(*p_, smc::wire::kConfigTopic);
    writer_.emplace(*topic_);
    reader_.emplace(*topic_, schema_);
    good_.set_config_id("good-1");
    good_.set_grafcet_text("grafcet x");
    publish_and_check(good_, std::nullopt);
    ASSERT_NE(reader_->current("mill-1"), nullptr);
  }

  void publish_and_check(const smc::config::SupervisorConfig& cfg,
                         std::optional<DocumentFault> expected,
                         const std::function<void(smc_data_Envelope&)>& corrupt = {},
                         const char* must_mention = nullptr) {
    smc_data_Envelope env;
    encode_envelope(cfg, schema_, "mill-1", cfg.config_id(), ++seq_, env);
    if (corrupt) corrupt(env);
    writer_->write(env);
    free_envelope(env);
    size_t accepted = 0;
    std::vector<EnvelopeRejection> errors;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (accepted + errors.size() == 0 && std::chrono::steady_clock::now() < deadline) {
      reader_->take([&](const std::string&, const smc::config::SupervisorConfig&) { ++accepted; },
                    [&](const EnvelopeRejection& e) { errors.push_back(e); });
      std::this_thread::sleep_for(2ms);
    }
    if (!expected) {
      EXPECT_EQ(accepted, 1u);
      EXPECT_TRUE(errors.empty());
      return;
    }
    EXPECT_EQ(accepted, 0u);
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].fault, *expected) << errors[0].message;
    EXPECT_EQ(errors[0].key, "mill-1");
    if (must_mention) {
      EXPECT_NE(errors[0].message.find(must_mention), std::string::npos) << errors[0].message;
    }
    // The configuration accepted before stays in force.
    ASSERT_NE(reader_->current("mill-1"), nullptr);
    EXPECT_EQ(reader_->current("mill-1")->config_id(), "good-1");
  }

  Schema schema_{"smc.config.SupervisorConfig", 1};
  std::string partition_;
  std::optional<Participant> p_;
  std::optional<Topic<smc_data_Envelope>> topic_;
  std::optional<Writer<smc_data_Envelope>> writer_;
  std::optional<DocumentReader<smc::config::SupervisorConfig>> reader_;
  smc::config::SupervisorConfig good_;
  uint64_t seq_ = 0;
};

TEST_F(BadEnvelope, WrongSchemaIsRejected) {
  smc::config::SupervisorConfig c;
  c.set_config_id("bad-schema");
  publish_and_check(
      c, DocumentFault::kWrongSchema,
      [](smc_data_Envelope& e) { set_string(e.schema, "smc.config.Job"); }, "smc.config.Job");
}

TEST_F(BadEnvelope, WrongVersionIsRejected) {
  smc::config::SupervisorConfig c;
  c.set_config_id("bad-version");
  publish_and_check(
      c, DocumentFault::kWrongVersion, [](smc_data_Envelope& e) { e.version = 2; }, "version 2");
}

TEST_F(BadEnvelope, TruncatedPayloadIsRejected) {
  smc::config::SupervisorConfig c;
  c.set_config_id("truncated");
  c.set_grafcet_text(std::string(200, 'x'));
  publish_and_check(
      c, DocumentFault::kTruncated, [](smc_data_Envelope& e) { e.payload._length -= 40; },
      "declared");
}

TEST_F(BadEnvelope, CorruptPayloadFailsChecksum) {
  smc::config::SupervisorConfig c;
  c.set_config_id("corrupt");
  c.set_grafcet_text("grafcet y");
  publish_and_check(
      c, DocumentFault::kBadChecksum, [](smc_data_Envelope& e) { e.payload._buffer[3] ^= 0x5A; },
      "CRC-32");
}

TEST_F(BadEnvelope, GarbageWithValidChecksumIsUnparsable) {
  smc::config::SupervisorConfig c;
  c.set_config_id("garbage");
  publish_and_check(
      c, DocumentFault::kUnparsable,
      [](smc_data_Envelope& e) {
        // 0xFF bytes are an invalid tag; recompute size and CRC so only parsing fails.
        for (uint32_t i = 0; i < e.payload._length; ++i) e.payload._buffer[i] = 0xFF;
        e.crc32 = crc32_of(e.payload._buffer, e.payload._length);
      },
      "could not parse");
}

// ---- per-machine partitions: a machine's participant speaks only for itself ----

TEST(MachinePartitions, NamesAreCheckedAndReadBack) {
  EXPECT_EQ(machine_partition("cell-a", "mill-1"), "cell-a/machine/mill-1");
  EXPECT_EQ(machine_partition("", "mill_1.b"), "/machine/mill_1.b");
  EXPECT_EQ(machine_of_partition("cell-a", "cell-a/machine/mill-1"), "mill-1");
  EXPECT_EQ(machine_of_partition("cell-a", "cell-b/machine/mill-1"), "");
  EXPECT_EQ(machine_of_partition("cell-a", "cell-a"), "");
  EXPECT_EQ(machine_of_partition("cell-a", "cell-a/machine/*"), "") << "a pattern is nobody's";
  for (const char* bad : {"", "-mill", "mill/2", "mill*", "mill 1", "mill\\1"}) {
    EXPECT_THROW(machine_partition("cell-a", bad), std::invalid_argument) << bad;
  }
  Participant mill1({.partition = smc::test::unique_partition("own"), .machine = "mill-1"});
  EXPECT_EQ(mill1.publisher_for("mill-1"), mill1.publisher());
  EXPECT_THROW(mill1.publisher_for("mill-2"), std::invalid_argument);
}

namespace {
std::vector<std::string> refusals;  // what the refusal handler was told
void record_refusal(const std::string& what) { refusals.push_back(what); }
// The machine ids of the first samples the reader takes (waiting up to 10 s
// for any): reliable and in order from one writer, so once one is taken the
// ones written before it have been judged too.
std::vector<std::string> first_machine_ids(Reader<smc_data_SupervisorSituation>& reader) {
  std::vector<std::string> seen;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (seen.empty() && std::chrono::steady_clock::now() < deadline) {
    reader.take([&](const smc_data_SupervisorSituation& x, const SampleInfo& i) {
      if (i.valid_data) seen.push_back(get_string(x.machine_id));
    });
    std::this_thread::sleep_for(2ms);
  }
  return seen;
}

}  // namespace

TEST(MachinePartitions, AMachinesWriterPosingAsAnotherMachineIsRefusedAndReported) {
  const std::string partition = smc::test::unique_partition("posing");
  Participant cell({.partition = partition});
  Participant mill1({.partition = partition, .machine = "mill-1"});
  Topic<smc_data_SupervisorSituation> cell_topic(cell);
  Topic<smc_data_SupervisorSituation> mill_topic(mill1);
  Reader<smc_data_SupervisorSituation> reader(cell_topic);
  Writer<smc_data_SupervisorSituation> writer(mill_topic);
  ASSERT_TRUE(writer.wait_for_readers(1, 10s));
  refusals.clear();
  set_refusal_handler(&record_refusal);
  smc_data_SupervisorSituation s{};
  set_string(s.machine_id, "mill-2");  // mill-1's edge, posing as mill-2
  writer.write(s);
  set_string(s.machine_id, "mill-1");  // and speaking for itself, after
  writer.write(s);
  // Reliable and in order from one writer: once mill-1's sample is in, the
  // one before it has been taken too.
  const std::vector<std::string> seen = first_machine_ids(reader);
  set_refusal_handler(nullptr);
  EXPECT_EQ(seen, std::vector<std::string>{"mill-1"});
  EXPECT_EQ(reader.refused(), 1u);
  ASSERT_EQ(refusals.size(), 1u);
  EXPECT_NE(refusals[0].find("smc_supervisor_situation"), std::string::npos) << refusals[0];
  EXPECT_NE(refusals[0].find("about machine 'mill-2'"), std::string::npos) << refusals[0];
  EXPECT_NE(refusals[0].find("machine 'mill-1''s partition"), std::string::npos) << refusals[0];
}

// A writer's partition is recorded when it matches: samples taken after the
// writer has gone (an edge's last progress, then its exit) are still judged
// by where they were written, in both directions.
TEST(MachinePartitions, SamplesTakenAfterTheirWriterHasGoneAreJudgedByItsPartition) {
  const std::string partition = smc::test::unique_partition("gone");
  Participant cell({.partition = partition});
  Topic<smc_data_SupervisorSituation> cell_topic(cell);
  Reader<smc_data_SupervisorSituation> reader(cell_topic);
  {
    Participant mill1({.partition = partition, .machine = "mill-1"});
    Topic<smc_data_SupervisorSituation> mill_topic(mill1);
    Writer<smc_data_SupervisorSituation> writer(mill_topic);
    ASSERT_TRUE(writer.wait_for_readers(1, 10s));
    smc_data_SupervisorSituation s{};
    set_string(s.machine_id, "mill-1");
    writer.write(s);
    set_string(s.machine_id, "mill-2");  // posing
    writer.write(s);
  }  // the writer's participant is deleted before anything is taken
  for (int i = 0; i < 5000 && reader.subscription_matched().current_count != 0; ++i) {
    std::this_thread::sleep_for(2ms);
  }
  ASSERT_EQ(reader.subscription_matched().current_count, 0u) << "the writer did not go";
  set_refusal_handler(&record_refusal);
  const std::vector<std::string> seen = first_machine_ids(reader);
  set_refusal_handler(nullptr);
  EXPECT_EQ(seen, std::vector<std::string>{"mill-1"});
  EXPECT_EQ(reader.refused(), 1u);
}

TEST(MachinePartitions, TheCellWritesIntoEachMachinesPartitionAndAMachineReadsOnlyItsOwn) {
  const std::string partition = smc::test::unique_partition("per-machine");
  Participant cell({.partition = partition});
  Participant mill1({.partition = partition, .machine = "mill-1"});
  Topic<smc_data_OperatorCommand> cell_topic(cell);
  Topic<smc_data_OperatorCommand> mill_topic(mill1);
  Reader<smc_data_OperatorCommand> at_mill1(mill_topic);
  Reader<smc_data_OperatorCommand> at_cell(cell_topic);  // every partition of the cell
  Writer<smc_data_OperatorCommand> in_cell(cell_topic);  // the cell's own partition
  Writer<smc_data_OperatorCommand> to_mill2(cell_topic, "mill-2");
  Writer<smc_data_OperatorCommand> to_mill1(cell_topic, "mill-1");
  ASSERT_TRUE(to_mill1.wait_for_readers(2, 10s));
  ASSERT_TRUE(to_mill2.wait_for_readers(1, 10s));
  ASSERT_TRUE(in_cell.wait_for_readers(1, 10s));
  smc_data_OperatorCommand c{};
  set_string(c.machine_id, "mill-1");
  c.command_id = 1;
  in_cell.write(c);  // a cell-partition writer: no edge reads it
  set_string(c.machine_id, "mill-2");
  c.command_id = 2;
  to_mill2.write(c);
  set_string(c.machine_id, "mill-1");
  c.command_id = 3;
  to_mill1.write(c);
  std::vector<uint64_t> mill_got, cell_got;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((mill_got.empty() || cell_got.size() < 3) && std::chrono::steady_clock::now() < deadline) {
    at_mill1.take([&](const smc_data_OperatorCommand& x, const SampleInfo& i) {
      if (i.valid_data) mill_got.push_back(x.command_id);
    });
    at_cell.take([&](const smc_data_OperatorCommand& x, const SampleInfo& i) {
      if (i.valid_data) cell_got.push_back(x.command_id);
    });
    std::this_thread::sleep_for(2ms);
  }
  std::sort(cell_got.begin(), cell_got.end());
  EXPECT_EQ(cell_got, (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(mill_got, std::vector<uint64_t>{3});
  EXPECT_EQ(to_mill2.publication_matched().current_count, 1u) << "only the cell's reader";
  EXPECT_EQ(in_cell.publication_matched().current_count, 1u) << "only the cell's reader";
  EXPECT_EQ(at_mill1.refused(), 0u);
  EXPECT_EQ(at_cell.refused(), 0u);
}

// ---- the error path names the failing call ----

TEST(ErrorPath, InvalidTopicNameNamesTheCall) {
  Participant p({.partition = smc::test::unique_partition("err")});
  try {
    Topic<smc_data_ForceSummary> t(p, "no spaces* allowed?");
    FAIL() << "an invalid topic name was accepted";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_create_topic(no spaces* allowed?)");
    EXPECT_LT(e.code(), 0);
    EXPECT_NE(std::string(e.what()).find("dds_create_topic"), std::string::npos);
  }
}

TEST(ErrorPath, InvalidQosNamesTheCall) {
  Participant p({.partition = smc::test::unique_partition("err")});
  Topic<smc_data_ForceSummary> t(p);
  QosProfile bad = QosProfile::telemetry(8).with_lease(std::chrono::nanoseconds(-5));
  try {
    Writer<smc_data_ForceSummary> w(t, bad);
    FAIL() << "a negative liveliness lease was accepted";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_create_writer(smc_force_summary)");
  }
}

TEST(ErrorPath, DeletedEntityNamesTheCall) {
  Participant p({.partition = smc::test::unique_partition("err")});
  Topic<smc_data_ForceSummary> t(p);
  Writer<smc_data_ForceSummary> w(t);
  Writer<smc_data_ForceSummary> moved(std::move(w));
  smc_data_ForceSummary s{};
  try {
    w.write(s);  // moved-from: handle 0
    FAIL() << "write on a moved-from writer succeeded";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_write");
  }
  EXPECT_NO_THROW(moved.write(s));
}
