// The model structs, their validation and the configuration documents.

#include "smc/machining/model.hpp"

#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "smc/machining/model_proto.hpp"
#include "smc/machining/paper_case.hpp"
#include "smc_config.pb.h"

namespace mc = smc::machining;

namespace {

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("smc_machining_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(PaperCase, IsTheAppendixModelAsData) {
  const mc::MillingModel m = mc::paper_case();
  EXPECT_EQ(m.cutter.teeth, 4);
  EXPECT_DOUBLE_EQ(m.cutter.radius_mm, 25);
  ASSERT_TRUE(std::holds_alternative<mc::PowerLaw>(m.law));
  const auto& law = std::get<mc::PowerLaw>(m.law);
  EXPECT_DOUBLE_EQ(law.cutting.coefficient_kn_per_mm2, 0.29);
  EXPECT_DOUBLE_EQ(law.thrust.depth_exponent, -0.41);
  ASSERT_EQ(m.structure.tool_x.size(), 1u);
  EXPECT_DOUBLE_EQ(m.structure.tool_x[0].natural_frequency_rad_s, 4500);
  EXPECT_DOUBLE_EQ(m.structure.part_y[0].damping_ratio, 0.22);
  EXPECT_DOUBLE_EQ(m.structure.part_x[0].stiffness_n_per_mm, 9500);
  EXPECT_EQ(m.delay, mc::DelayKind::tooth_period);
  ASSERT_TRUE(m.reference_cut.has_value());
  EXPECT_DOUBLE_EQ(m.reference_cut->spindle_rpm, 1500);
  EXPECT_DOUBLE_EQ(mc::feed_per_tooth_mm(m.reference_cut->feedrate_mm_s, 1500, 4), 0.1);
  // The embedded document is the file in cell/models.
  EXPECT_EQ(
      mc::load_milling_model(std::string(SMC_SOURCE_DIR) + "/cell/models/paper_face_mill.textproto")
          .workpiece.width_mm,
      m.workpiece.width_mm);
  const mc::ForceProcessModel f = mc::paper_force_process_model();
  EXPECT_DOUBLE_EQ(f.k_kn, 0.76);
  EXPECT_DOUBLE_EQ(f.beta, 0.65);
  EXPECT_DOUBLE_EQ(f.alpha, 0.63);
}

TEST(Validation, NamesTheFieldPathRangeAndValue) {
  smc::config::MillingModel msg = mc::to_proto(mc::paper_case());
  msg.mutable_structure()->mutable_tool_x(0)->set_damping_ratio(1.7);
  const std::string e = error_of([&] { mc::from_proto(msg); });
  EXPECT_EQ(e, "milling_model.structure.tool_x[0].damping_ratio: must be in (0, 1), got 1.7");
}

TEST(Validation, ReportsEveryErrorAndUsesThePrefix) {
  smc::config::MillingModel msg = mc::to_proto(mc::paper_case());
  msg.mutable_cutter()->set_teeth(0);
  msg.mutable_workpiece()->set_width_mm(-3);
  msg.mutable_structure()->mutable_part_y(0)->set_stiffness_n_per_mm(0);
  msg.mutable_law()->mutable_power_law()->mutable_cutting()->set_feed_exponent(-1.5);
  try {
    mc::from_proto(msg, "config.milling_model");
    FAIL() << "accepted";
  } catch (const mc::ModelError& e) {
    ASSERT_EQ(e.errors().size(), 4u) << e.what();
    EXPECT_EQ(e.errors()[0], "config.milling_model.cutter.teeth: must be >= 1, got 0");
    EXPECT_EQ(e.errors()[1], "config.milling_model.workpiece.width_mm: must be > 0, got -3");
    EXPECT_EQ(e.errors()[2],
              "config.milling_model.law.power_law.cutting.feed_exponent: must be > -1, got -1.5");
    EXPECT_EQ(e.errors()[3],
              "config.milling_model.structure.part_y[0].stiffness_n_per_mm: must be > 0, got 0");
  }
}

TEST(Validation, MissingLawStructureAndUnreachablePart) {
  smc::config::MillingModel msg = mc::to_proto(mc::paper_case());
  msg.clear_law();
  msg.clear_structure();
  msg.mutable_workpiece()->set_offset_mm(60);
  const std::string e = error_of([&] { mc::from_proto(msg); });
  EXPECT_NE(e.find("milling_model.law: not set"), std::string::npos) << e;
  EXPECT_NE(e.find("milling_model.structure: has no modes"), std::string::npos) << e;
  EXPECT_NE(e.find("milling_model.workpiece.offset_mm: puts the part's width band"),
            std::string::npos)
      << e;
}

TEST(Validation, NonFiniteValuesAreRejected) {
  mc::MillingModel m = mc::paper_case();
  m.structure.tool_y[0].natural_frequency_rad_s = std::nan("");
  m.internal_step_s = 1e-3;
  const auto errors = mc::validation_errors(m);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0],
            "milling_model.structure.tool_y[0].natural_frequency_rad_s: must be > 0, got nan");
  EXPECT_NE(errors[1].find("milling_model.internal_step_s: must be in [1e-7, 1e-4] s"),
            std::string::npos);
  EXPECT_THROW(mc::validate(mc::CutConditions{0, 0.1, 1}), std::invalid_argument);
  EXPECT_THROW(mc::validate(mc::CutConditions{1500, -0.1, 1}), std::invalid_argument);
  EXPECT_NO_THROW(mc::validate(mc::CutConditions{1500, 0, 0}));
}

// Issue: a 1e-12 s step was accepted and then refused later for "spindle
// speed too low".
TEST(Validation, AnAbsurdlySmallInternalStepIsRefusedForWhatItIs) {
  mc::MillingModel m = mc::paper_case();
  m.internal_step_s = 1e-12;
  const auto errors = mc::validation_errors(m);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("milling_model.internal_step_s: must be in [1e-7, 1e-4] s"),
            std::string::npos)
      << errors[0];
  EXPECT_NE(errors[0].find("got 1e-12"), std::string::npos) << errors[0];
}

TEST(Documents, RoundTripThroughProto) {
  mc::MillingModel m = mc::paper_case();
  m.structure.tool_x.push_back(mc::Mode{9000, 0.03, 30000});
  m.delay = mc::DelayKind::spindle_revolution;
  m.workpiece.down_milling = true;
  const mc::MillingModel back = mc::from_proto(mc::to_proto(m));
  EXPECT_EQ(back.name, m.name);
  EXPECT_EQ(back.structure.tool_x.size(), 2u);
  EXPECT_DOUBLE_EQ(back.structure.tool_x[1].natural_frequency_rad_s, 9000);
  EXPECT_EQ(back.delay, mc::DelayKind::spindle_revolution);
  EXPECT_TRUE(back.workpiece.down_milling);
  EXPECT_DOUBLE_EQ(back.cutter.lead_angle_deg, m.cutter.lead_angle_deg);
  EXPECT_DOUBLE_EQ(back.internal_step_s, m.internal_step_s);

  mc::MillingModel lin = m;
  lin.law = mc::LinearLaw{800, 300, 50};
  const auto back_lin = mc::from_proto(mc::to_proto(lin));
  ASSERT_TRUE(std::holds_alternative<mc::LinearLaw>(back_lin.law));
  EXPECT_DOUBLE_EQ(std::get<mc::LinearLaw>(back_lin.law).k_a_n_per_mm2, 50);

  smc::config::MillingModel msg = mc::to_proto(m);
  msg.set_internal_step_s(0);
  msg.set_delay(smc::config::DELAY_UNSPECIFIED);
  const mc::MillingModel defaults = mc::from_proto(msg);
  EXPECT_DOUBLE_EQ(defaults.internal_step_s, mc::kDefaultInternalStepS);
  EXPECT_EQ(defaults.delay, mc::DelayKind::tooth_period);
}

TEST(Documents, LoadsJsonAndTextFilesAndNamesTheFileInErrors) {
  std::string json;
  ASSERT_TRUE(
      google::protobuf::util::MessageToJsonString(mc::to_proto(mc::paper_case()), &json).ok());
  const auto json_file = temp_file("model.json", json);
  EXPECT_EQ(mc::load_milling_model(json_file).cutter.teeth, 4);

  const auto bad_syntax = temp_file("bad.textproto", "name: \"x\"\ncutter { teeth: four }\n");
  const std::string e1 = error_of([&] { mc::load_milling_model(bad_syntax); });
  EXPECT_EQ(e1.rfind(bad_syntax.string() + ":2:17: ", 0), 0u) << e1;

  std::string text = std::string(mc::paper_case_text());
  const std::string part_x_damping = "damping_ratio: 0.09";
  ASSERT_NE(text.find(part_x_damping), std::string::npos);
  text.replace(text.find(part_x_damping), part_x_damping.size(), "damping_ratio: 2");
  const auto bad_value = temp_file("bad_value.textproto", text);
  const std::string e2 = error_of([&] { mc::load_milling_model(bad_value); });
  EXPECT_EQ(e2, bad_value.string() +
                    ": milling_model.structure.part_x[0].damping_ratio: must be in (0, 1), got 2");

  const std::string e3 = error_of([] { mc::load_milling_model("/nonexistent/model.textproto"); });
  EXPECT_NE(e3.find("/nonexistent/model.textproto: cannot open"), std::string::npos) << e3;
  for (const auto& p : {json_file, bad_syntax, bad_value}) std::filesystem::remove(p);
}

TEST(Documents, ForceProcessModelRoundTripAndValidation) {
  mc::ForceProcessModel f = mc::paper_force_process_model();
  f.fit = mc::FitStatistics{12, 0.98, 3.5, 0.01, 0.02, 0.03};
  const mc::ForceProcessModel back = mc::from_proto(mc::to_proto(f));
  EXPECT_DOUBLE_EQ(back.k_kn, 0.76);
  ASSERT_TRUE(back.fit.has_value());
  EXPECT_EQ(back.fit->samples, 12u);
  EXPECT_DOUBLE_EQ(back.fit->alpha_stderr, 0.03);
  smc::config::ForceProcessModel msg = mc::to_proto(f);
  msg.set_k_kn(-1);
  EXPECT_EQ(error_of([&] { mc::from_proto(msg); }), "force_model.k_kn: must be > 0, got -1");
}

TEST(Units, FeedPerToothPeriodAndDelay) {
  const mc::MillingModel m = mc::paper_case();
  EXPECT_DOUBLE_EQ(mc::feed_per_tooth_mm(10, 1500, 4), 0.1);
  EXPECT_DOUBLE_EQ(mc::feed_per_tooth_mm(10, 0, 4), 0);
  EXPECT_DOUBLE_EQ(mc::tooth_period_s(1500, 4), 0.01);
  EXPECT_DOUBLE_EQ(mc::delay_s(m, 1500), 0.01);
  mc::MillingModel rev = m;
  rev.delay = mc::DelayKind::spindle_revolution;
  EXPECT_DOUBLE_EQ(mc::delay_s(rev, 1500), 0.04);
}
