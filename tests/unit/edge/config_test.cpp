// Bad configurations are refused with an error naming the field and the fix;
// nothing half-built is ever used.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "edge_test_config.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/replay_drive.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc_config.pb.h"

using namespace smc::edge;

namespace {

void expect_refused(const smc::config::SupervisorConfig& cfg, const std::string& must_mention) {
  try {
    (void)edge_config_from_proto(cfg);
    ADD_FAILURE() << "accepted a configuration that should fail on " << must_mention;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(must_mention), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(EdgeConfig, ShippedConfigurationsAreValid) {
  for (const char* name :
       {"no_control.textproto", "smc1.textproto", "smc1_guarded.textproto", "smc2.textproto"}) {
    EXPECT_NO_THROW((void)edge_config_from_proto(test::shipped_config(name))) << name;
  }
}

TEST(EdgeConfig, OutOfLimitFeedIsRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_program()->mutable_passes(0)->set_feedrate_mm_s(50);
  expect_refused(cfg, "program.passes[0].feedrate_mm_s");
}

TEST(EdgeConfig, FeedPerToothAboveTheHandbookLimitIsRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_operation()->set_max_feed_per_tooth_mm(0.05);
  expect_refused(cfg, "mm/tooth, above the operation's limit");
}

TEST(EdgeConfig, NonPositiveParametersNameTheField) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_operation()->set_sample_period_s(0);
  expect_refused(cfg, "supervisor_config.operation.sample_period_s");
  cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_machine()->set_max_spindle_power_w(std::nan(""));
  expect_refused(cfg, "supervisor_config.machine.max_spindle_power_w");
}

TEST(EdgeConfig, UnknownModuleLetterIsRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.add_modules("Q");
  expect_refused(cfg, "modules[");
}

TEST(EdgeConfig, ModelBasedControlWithoutAModelIsRefused) {
  auto cfg = test::shipped_config("smc1.textproto");
  cfg.clear_force_model();
  expect_refused(cfg, "force_model");
}

TEST(EdgeConfig, GrafcetParseErrorsCarryTheirPosition) {
  auto cfg = test::shipped_config("smc1.textproto");
  cfg.set_grafcet_name("broken.grafcet");
  cfg.set_grafcet_text("this is not a grafcet\n");
  expect_refused(cfg, "broken.grafcet:1:");
}

TEST(EdgeConfig, GrafcetActionOutsideTheModuleSetIsRefused) {
  auto cfg = test::shipped_config("smc1.textproto");
  cfg.clear_modules();
  for (const char* m : {"A", "B", "C", "I", "J"}) cfg.add_modules(m);  // no L
  cfg.clear_force_model();
  expect_refused(cfg, "action 'L'");
}

TEST(EdgeConfig, SpindleSpeedBelowTheSupervisedRangeIsRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_program()->mutable_passes(0)->set_spindle_rpm(700);  // range: 750-3000 rpm
  expect_refused(cfg, "passes[0].spindle_rpm");
  cfg.mutable_machine()->set_min_spindle_rpm(500);
  EXPECT_NO_THROW((void)edge_config_from_proto(cfg));
  cfg.mutable_machine()->set_min_spindle_rpm(3500);
  expect_refused(cfg, "machine.min_spindle_rpm");
}

TEST(EdgeConfig, AnySpeedInTheRangeIsAcceptedWhateverTheSlowPeriod) {
  // 1100 rpm is 109.09 samples per revolution at 0.5 ms: the revolution
  // clock follows the measured speed, not slow_period_s.
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.mutable_program()->mutable_passes(0)->set_spindle_rpm(1100);
  EXPECT_NO_THROW((void)edge_config_from_proto(cfg));
}

// A configuration whose module E expects another count of wideband samples
// than its simulated mill gives is refused before it runs (the edge's
// intake and `smc-edge simulate` call this), not held at the first contact.
// E judging S alone never reads the channel, so there it does not matter.
TEST(EdgeConfig, AWidebandChannelTheSimulatedMillDoesNotGiveIsRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  EXPECT_NO_THROW(check_wideband_channel_agrees(cfg));
  cfg.mutable_operation()->set_wideband_samples_per_tick(1);
  try {
    check_wideband_channel_agrees(cfg);
    ADD_FAILURE() << "accepted E at 1 sample a period on a mill that gives 5";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("operation.wideband_samples_per_tick: module E expects 1 wideband "
                        "samples a period, but the simulated mill gives 5"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("fix:"), std::string::npos) << what;
  }
  cfg.mutable_simulation()->set_f_y_wide_samples_per_tick(0);  // 0: one a period
  EXPECT_NO_THROW(check_wideband_channel_agrees(cfg));
  cfg.mutable_simulation()->set_f_y_wide_samples_per_tick(2);
  EXPECT_THROW(check_wideband_channel_agrees(cfg), ConfigError);
  cfg.mutable_milling_model()->mutable_structure()->clear_tool_y();
  cfg.mutable_milling_model()->mutable_structure()->clear_part_y();
  EXPECT_NO_THROW(check_wideband_channel_agrees(cfg)) << "S alone reads no wideband channel";
}

TEST(ReplayDrive, MalformedRowsNameFileLineAndColumn) {
  const std::string path = ::testing::TempDir() + "/replay_bad.csv";
  {
    std::ofstream f(path);
    f << "t_s,f_y_n,f_z_n\n0.0005,10,20\n0.001,abc,20\n";
  }
  try {
    ReplayDrive d(path, 0.0005);
    FAIL() << "accepted a malformed file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":3: column 'f_y_n'"), std::string::npos) << e.what();
  }
  {
    std::ofstream f(path);
    f << "t_s,f_y_n\n0.0005,10\n";
  }
  try {
    ReplayDrive d(path, 0.0005);
    FAIL() << "accepted a file without f_z_n";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("f_z_n"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

// The wideband F_y channel (module E's vibration estimate) is an optional
// column, as `smc-edge simulate` writes it; without it the drive has no such
// channel (NaN), and E judges F_z alone.
TEST(ReplayDrive, TheWidebandFyColumnIsOptional) {
  const std::string with = ::testing::TempDir() + "/replay_wide.csv";
  const std::string without = ::testing::TempDir() + "/replay_narrow.csv";
  {
    std::ofstream f(with);
    f << "t_s,f_y_n,f_z_n,f_y_wide_n\n0.0005,10,20,11.5\n";
    std::ofstream g(without);
    g << "t_s,f_y_n,f_z_n\n0.0005,10,20\n";
  }
  FixedProgram p;
  p.count = 1;
  p.passes[0] = {2, 10, 1500};
  DriveSample s;
  ReplayDrive a(with, 0.0005);
  a.load(p);
  ASSERT_EQ(a.step(0, s), Status::kOk);
  EXPECT_EQ(s.force.f_y_wide_n, 11.5);
  ReplayDrive b(without, 0.0005);
  b.load(p);
  ASSERT_EQ(b.step(0, s), Status::kOk);
  EXPECT_TRUE(std::isnan(s.force.f_y_wide_n));
  std::remove(with.c_str());
  std::remove(without.c_str());
}

TEST(ReplayDrive, PlaysSamplesInOrderAndKeepsNaNForTheCore) {
  const std::string path = ::testing::TempDir() + "/replay_ok.csv";
  {
    std::ofstream f(path);
    f << "t_s,f_y_n,f_z_n,in_pass\n0.0005,10,20,1\n0.001,nan,21,1\n0.0015,12,22,0\n";
  }
  ReplayDrive d(path, 0.0005);
  FixedProgram p;
  p.count = 1;
  p.passes[0] = {2, 10, 1500};
  d.load(p);
  DriveSample s;
  ASSERT_EQ(d.step(0, s), Status::kOk);
  EXPECT_EQ(s.force.f_y_n, 10);
  EXPECT_DOUBLE_EQ(s.depth_mm, 2);
  d.step(0, s);
  EXPECT_TRUE(std::isnan(s.force.f_y_n));
  d.step(0, s);
  EXPECT_FALSE(s.in_pass);
  EXPECT_TRUE(s.program_done);
  std::remove(path.c_str());
}
