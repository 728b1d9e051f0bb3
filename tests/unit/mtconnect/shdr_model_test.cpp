// ShdrModel: what each DDS sample becomes in SHDR, line by line.

#include "smc/mtconnect/shdr_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"
#include "smc_data.h"

namespace mt = smc::mtconnect;

namespace {

constexpr std::int64_t kT = 1'790'000'000'000'000'000;  // 2026-09-21

smc_data_EdgeStatus status(smc_data_EdgeState state, const char* message = "") {
  smc_data_EdgeStatus s{};
  smc::wire::set_string(s.machine_id, "mill-1");
  smc::wire::set_string(s.job_id, "job-000007");
  smc::wire::set_string(s.message, message);
  s.state = state;
  return s;
}

bool has(const std::vector<std::string>& lines, const std::string& tail) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
    return l.size() >= tail.size() && l.compare(l.size() - tail.size(), tail.size(), tail) == 0;
  });
}

}  // namespace

TEST(ShdrModel, TimestampsAreUtcWithMicroseconds) {
  EXPECT_EQ(mt::shdr_time(0), "1970-01-01T00:00:00.000000Z");
  EXPECT_EQ(mt::shdr_time(1'500'000'000'123'456'789), "2017-07-14T02:40:00.123456Z");
}

TEST(ShdrModel, ExecutionFollowsTheEdgeAndItsFeedHold) {
  mt::ShdrModel m;
  auto l = m.on_status(status(smc_data_EDGE_CONFIGURED), kT);
  EXPECT_TRUE(has(l, "|mill-1:avail|AVAILABLE"));
  EXPECT_TRUE(has(l, "|mill-1:exec|READY"));
  EXPECT_TRUE(has(l, "|mill-1:program|job-000007"));
  EXPECT_TRUE(has(l, "|mill-1:edge_fault|NORMAL||||"));
  EXPECT_EQ(l.front().substr(0, 27), mt::shdr_time(kT));
  l = m.on_status(status(smc_data_EDGE_RUNNING), kT + 1);
  EXPECT_EQ(l, std::vector<std::string>{mt::shdr_time(kT + 1) + "|mill-1:exec|ACTIVE"})
      << "only what changed";
  smc_data_SupervisorSituation s{};
  smc::wire::set_string(s.machine_id, "mill-1");
  s.modules_active = 1u << 2;  // C: feed hold
  EXPECT_TRUE(has(m.on_situation(s, kT + 2), "|mill-1:exec|FEED_HOLD"));
  s.modules_active = 0;
  EXPECT_TRUE(has(m.on_situation(s, kT + 3), "|mill-1:exec|ACTIVE"));
  l = m.on_status(status(smc_data_EDGE_FAULT, "non-finite force | sample"), kT + 4);
  EXPECT_TRUE(has(l, "|mill-1:exec|INTERRUPTED"));
  EXPECT_TRUE(has(l, "|mill-1:edge_fault|FAULT|EDGE_FAULT||HIGH|non-finite force   sample"))
      << "a '|' in the text would split the line";
  smc_data_JobProgress p{};
  smc::wire::set_string(p.machine_id, "mill-1");
  smc::wire::set_string(p.job_id, "job-000007");
  p.phase = smc_data_JOB_DONE;
  m.on_status(status(smc_data_EDGE_RUNNING), kT + 5);
  EXPECT_TRUE(has(m.on_progress(p, kT + 6), "|mill-1:exec|PROGRAM_COMPLETED"));
}

TEST(ShdrModel, ChatterIsAWarningUntilTheEdgeCutsWithoutIt) {
  mt::ShdrModel m(0);
  m.on_status(status(smc_data_EDGE_RUNNING), kT);
  smc_data_ChatterEvent e{};
  smc::wire::set_string(e.machine_id, "mill-1");
  smc::wire::set_string(e.job_id, "job-000007");
  e.source = smc_data_CHATTER_AUTOMATIC;
  e.frequency_hz = 749.7f;
  e.machine_time_ns = 3'000'000'000;
  e.new_pass_count = 2;
  const auto l = m.on_chatter(e, kT + 1);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_TRUE(has(l,
                  "|mill-1:chatter|WARNING|CHATTER_AUTOMATIC||HIGH|chatter detected in pass 1 "
                  "at 750 Hz; program now 2 passes (job job-000007)"))
      << l[0];
  smc_data_ForceSummary f{};
  smc::wire::set_string(f.machine_id, "mill-1");
  f.in_contact = true;
  f.pass_count = 2;
  f.machine_time_ns = 3'500'000'000;  // still within a second of it
  EXPECT_FALSE(has(m.on_summary(f, kT + 2), "|mill-1:chatter|NORMAL||||"));
  f.machine_time_ns = 4'100'000'000;
  EXPECT_TRUE(has(m.on_summary(f, kT + 3), "|mill-1:chatter|NORMAL||||"));
}

// SMC II+: the speed change is the chatter's remedy in its message, and a
// job that module N stopped makes the tool condition a fault until the next
// job runs.
TEST(ShdrModel, ASpeedChangeIsTheRemedyAndABreakageIsAToolFault) {
  mt::ShdrModel m(0);
  m.on_status(status(smc_data_EDGE_RUNNING), kT);
  smc_data_ChatterEvent e{};
  smc::wire::set_string(e.machine_id, "mill-1");
  smc::wire::set_string(e.job_id, "job-000008");
  e.source = smc_data_CHATTER_AUTOMATIC;
  e.frequency_hz = 749.7f;
  e.new_pass_count = 1;
  e.new_spindle_rpm = 2700;
  EXPECT_TRUE(has(m.on_chatter(e, kT + 1),
                  "|mill-1:chatter|WARNING|CHATTER_AUTOMATIC||HIGH|chatter detected in pass 1 "
                  "at 750 Hz; spindle speed now 2700 rpm (job job-000008)"));
  smc_data_JobProgress p{};
  smc::wire::set_string(p.machine_id, "mill-1");
  smc::wire::set_string(p.job_id, "job-000008");
  smc::wire::set_string(p.message, "tool breakage at 12.505 s in pass 1: tooth window 4 lost 65 %");
  p.phase = smc_data_JOB_FAILED;
  EXPECT_TRUE(has(m.on_progress(p, kT + 2),
                  "|mill-1:tool|FAULT|TOOL_BREAKAGE||HIGH|tool breakage at 12.505 s in pass 1: "
                  "tooth window 4 lost 65 % (job job-000008)"));
  smc::wire::set_string(p.job_id, "job-000009");
  smc::wire::set_string(p.message, "");
  p.phase = smc_data_JOB_RUNNING;
  EXPECT_TRUE(has(m.on_progress(p, kT + 3), "|mill-1:tool|NORMAL||||"));
  // Another job's failure is no tool fault.
  smc::wire::set_string(p.message, "stopped before the end");
  p.phase = smc_data_JOB_FAILED;
  EXPECT_FALSE(has(m.on_progress(p, kT + 4), "|mill-1:tool|FAULT"));
}

TEST(ShdrModel, SamplesAreRateLimitedAndFeedOverrideIsAgainstTheProgram) {
  mt::ShdrModel m(100'000'000);
  smc::config::SupervisorConfig c;
  c.set_variant(smc::config::SMC_II);
  c.set_grafcet_name("smc2");
  c.mutable_program()->add_passes()->set_feedrate_mm_s(10);
  EXPECT_TRUE(has(m.on_config("mill-1", c, kT), "|mill-1:smc|SMC II (job shop), supervisor smc2"));
  smc_data_ForceSummary f{};
  smc::wire::set_string(f.machine_id, "mill-1");
  f.spindle_rpm = 1500;
  f.feedrate_mm_s = 8;
  f.f_y_peak_n = 180.4f;
  f.spindle_power_w = std::numeric_limits<float>::quiet_NaN();
  f.pass_count = 1;
  auto l = m.on_summary(f, kT + 200'000'000);
  EXPECT_TRUE(has(l, "|mill-1:Srpm|1500.0"));
  EXPECT_TRUE(has(l, "|mill-1:feed_ovr|80.0"));
  EXPECT_TRUE(has(l, "|mill-1:Fy|180.4"));
  EXPECT_TRUE(has(l, "|mill-1:block|pass 1 of 1"));
  // No power signal: the item stays UNAVAILABLE (nothing new to send).
  EXPECT_TRUE(has(m.snapshot(kT), "|mill-1:power|UNAVAILABLE"));
  f.f_y_peak_n = 190;
  EXPECT_FALSE(has(m.on_summary(f, kT + 250'000'000), "|mill-1:Fy|190.0")) << "within 100 ms";
  EXPECT_TRUE(has(m.on_summary(f, kT + 310'000'000), "|mill-1:Fy|190.0"));
}

TEST(ShdrModel, AGoneEdgeMakesItsMillUnavailableAndANewAgentGetsEverything) {
  mt::ShdrModel m;
  m.on_status(status(smc_data_EDGE_RUNNING), kT);
  const auto l = m.on_gone("mill-1", kT + 1);
  EXPECT_TRUE(has(l, "|mill-1:avail|UNAVAILABLE"));
  EXPECT_TRUE(has(l, "|mill-1:exec|UNAVAILABLE"));
  EXPECT_TRUE(has(l, "|mill-1:edge_fault|UNAVAILABLE||||"));
  const auto snap = m.snapshot(kT + 2);
  EXPECT_EQ(snap.size(), 13u) << "every data item of the mill";
  EXPECT_TRUE(has(snap, "|mill-1:program|job-000007"));
}

TEST(ShdrModel, TheDeviceFileDeclaresEveryItemOnce) {
  const std::string x = mt::devices_xml({"mill-1", "mill-2"});
  for (const char* item : {"avail", "exec", "program", "block", "smc", "Srpm", "path_feedrate",
                           "feed_ovr", "Fy", "power", "chatter", "tool", "edge_fault"}) {
    const std::string id = std::string("id=\"mill-2_") + item + "\"";
    EXPECT_NE(x.find(id), std::string::npos) << item;
    EXPECT_EQ(x.find(id), x.rfind(id)) << item;
  }
}
