// The cell's choices as pure functions: SMC selection, planning, dispatch and
// the lost-edge policy, without DDS. Planning uses the shipped Grafcets,
// defaults and the paper's models from the seeded store.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "smc/cell/dispatch.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/power_plan.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/supervision/parameters.hpp"

namespace cell = smc::cell;
namespace store = smc::cell::store;
namespace cfg = smc::config;

namespace {

std::string src(const std::string& rel) { return std::string(SMC_SOURCE_DIR) + "/" + rel; }

// The seeded demo cell, once for the whole suite.
class CellChoices : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() / ("smc-choices-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    db_ = new store::Store(store::Store::open((dir_ / "cell.db").string()));
    store::seed_demo(*db_, {store::default_models_dir()});
    cfg::SupervisorConfig defaults;
    smc::documents::load(src("cell/configs/defaults.textproto"), defaults);
    planner_ = new cell::Planner(src("cell/grafcets"), defaults);
  }
  static void TearDownTestSuite() {
    delete planner_;
    delete db_;
    std::filesystem::remove_all(dir_);
  }

  static cell::PlanInputs inputs(const std::string& part_id, double depth_mm = 0) {
    cfg::Job spec;
    spec.set_part_id(part_id);
    if (depth_mm > 0) spec.set_depth_mm(depth_mm);
    const auto job = db_->submit_job(spec);
    const auto part = *db_->part(job.spec.part_id());
    const auto tool = *db_->tool(job.spec.tool_id());
    return {job, part, tool, db_->find_models("mill-1", tool.id, part.material_id, part.id)};
  }

  static inline std::filesystem::path dir_;
  static inline store::Store* db_ = nullptr;
  static inline cell::Planner* planner_ = nullptr;
};

std::string modules_of(const cfg::SupervisorConfig& c) {
  std::string m;
  for (const auto& x : c.modules()) m += x;
  return m;
}

store::ProcessModel model(store::ModelKind kind, bool validated, const std::string& id) {
  store::ProcessModel m;
  m.id = id;
  m.kind = kind;
  m.validated = validated;
  m.provenance = cfg::PROVENANCE_IDENTIFIED;
  return m;
}

}  // namespace

// ---- selection

TEST(Selection, NoModelsGiveSmcII) {
  cell::PlanInputs in;
  in.tool.id = "fm";
  in.part.material_id = "al";
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("none"), std::string::npos) << sel.explanation;
  EXPECT_NE(sel.explanation.find("no validated models"), std::string::npos) << sel.explanation;
}

TEST(Selection, AForceModelAloneNamesTheMissingStructuralModel) {
  cell::PlanInputs in;
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1")};
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("no validated structural model"), std::string::npos)
      << sel.explanation;
}

TEST(Selection, BothValidatedGiveSmcIAndUnvalidatedOnesAreListedButNotUsed) {
  cell::PlanInputs in;
  in.models = {model(store::ModelKind::kForceProcess, false, "model-1"),
               model(store::ModelKind::kForceProcess, true, "model-2"),
               model(store::ModelKind::kMilling, true, "model-3")};
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_I);
  ASSERT_TRUE(sel.force);
  EXPECT_EQ(sel.force->id, "model-2");
  EXPECT_EQ(sel.milling->id, "model-3");
  for (const char* id : {"model-1", "model-2", "model-3"}) {
    EXPECT_NE(sel.explanation.find(id), std::string::npos) << id << ": " << sel.explanation;
  }
  EXPECT_NE(sel.explanation.find("not validated"), std::string::npos) << sel.explanation;
}

TEST(Selection, AnUnvalidatedStructuralModelDoesNotMakeSmcI) {
  cell::PlanInputs in;
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1"),
               model(store::ModelKind::kMilling, false, "model-2")};
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_II);
}

// ---- planning

// SMC I: each pass's F_ref is planned from the models so that the planned
// cut's mean spindle power is the share of the machine's limit that module M
// holds (not the paper's P_max / V, which puts it ~14 % above the limit).
TEST_F(CellChoices, TheSmcIPlanSetsEachPassesForceReferenceForTheMachinesPower) {
  const auto in = inputs("bracket-tl");
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_I) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  store::Machine machine;
  machine.id = "mill-x";
  machine.max_spindle_power_w = 745.7;
  machine.max_feedrate_mm_s = 36;
  machine.max_spindle_rpm = 3000;
  const auto c = cell::Planner::for_machine(plan.config, machine, "c-1");
  const double v = smc::supervision::cutting_speed_m_s(in.tool.radius_mm, 1500);
  const double papers = 745.7 / v;  // 190 N
  for (const auto& p : c.program().passes()) {
    const double rho = cell::power_force_ratio(c.milling_model(), p.depth_mm(), 1500,
                                               smc::supervision::feed_per_tooth_mm(10, 4, 1500));
    EXPECT_GT(rho, 1.05) << "two teeth in the cut: the mean power exceeds V F_Y";
    EXPECT_NEAR(p.force_reference_n(), 0.95 * 745.7 / (v * rho), 1e-9);
    EXPECT_LT(p.force_reference_n(), 0.9 * papers);
  }
  // Half the power, half the force.
  machine.max_spindle_power_w = 745.7 / 2;
  const auto half = cell::Planner::for_machine(plan.config, machine, "c-2");
  EXPECT_NEAR(half.program().passes(0).force_reference_n(),
              c.program().passes(0).force_reference_n() / 2, 1e-9);
  // SMC II plans carry no planned F_ref (the edge learns the ratio).
  const auto js = inputs("housing-js");
  const auto js_plan = planner_->plan(js, cell::select_variant(js));
  const auto js_c = cell::Planner::for_machine(js_plan.config, machine, "c-3");
  EXPECT_EQ(js_c.program().passes(0).force_reference_n(), 0);
}

TEST_F(CellChoices, TransferLinePartIsPlannedAsTwoEqualChatterFreePasses) {
  const auto in = inputs("bracket-tl");
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_I) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  // The physics' critical depth at 1500 rpm and 0.1 mm/tooth is 1.839 mm.
  EXPECT_NEAR(plan.critical_depth_mm, 1.84, 0.02);
  const auto& prog = plan.config.program();
  ASSERT_EQ(prog.passes_size(), 2);
  for (const auto& p : prog.passes()) {
    EXPECT_DOUBLE_EQ(p.depth_mm(), 1.0);
    EXPECT_DOUBLE_EQ(p.spindle_rpm(), 1500);
    EXPECT_DOUBLE_EQ(p.feedrate_mm_s(), 10);
  }
  EXPECT_EQ(modules_of(plan.config), "ABCIJLM");
  EXPECT_EQ(plan.config.grafcet_name(), "smc1.grafcet");
  EXPECT_TRUE(plan.config.has_force_model());
  EXPECT_NEAR(plan.config.operation().slow_period_s(), 0.04, 1e-12);  // one revolution
  EXPECT_NE(plan.config.explanation().find("2 equal passes of 1 mm"), std::string::npos)
      << plan.config.explanation();
}

TEST_F(CellChoices, JobShopPartRunsAsProgrammedUnderSmcII) {
  const auto in = inputs("housing-js");
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_II) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  ASSERT_EQ(plan.config.program().passes_size(), 1);
  EXPECT_DOUBLE_EQ(plan.config.program().passes(0).depth_mm(), 2.0);
  EXPECT_EQ(modules_of(plan.config), "ABCDEFGHIJKM");
  EXPECT_EQ(plan.config.grafcet_name(), "smc2.grafcet");
  EXPECT_FALSE(plan.config.has_force_model());
  EXPECT_LT(plan.critical_depth_mm, 0);  // no stability analysis without models
}

TEST_F(CellChoices, ADepthNeedingMoreThanSixteenPassesIsRefusedNamingTheJob) {
  auto in = inputs("bracket-tl", 40);  // 40 mm at 0.8 x 1.84 mm a pass: 28 passes
  const auto sel = cell::select_variant(in);
  try {
    (void)planner_->plan(in, sel);
    FAIL() << "planned more passes than a program holds";
  } catch (const std::runtime_error& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("job " + in.job.id), std::string::npos) << why;
    EXPECT_NE(why.find("(at most 16)"), std::string::npos) << why;
  }
}

TEST_F(CellChoices, AZeroSpindleSpeedIsRefusedNamingTheJob) {
  auto in = inputs("housing-js");
  in.job.spec.set_spindle_rpm(0);
  try {
    (void)planner_->plan(in, cell::select_variant(in));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("spindle_rpm must be > 0"), std::string::npos) << e.what();
  }
}

// ---- dispatch

TEST(Dispatch, HigherPriorityFirstThenSubmissionOrder) {
  const std::vector<cell::PlannedJob> planned = {
      {"j1", 1, "", 0}, {"j2", 5, "", 0}, {"j3", 5, "", 2}};
  const std::vector<cell::MillView> mills = {{"mill-1", true, true}, {"mill-2", true, true}};
  const auto a = cell::choose_assignments(planned, mills, {});
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].job_id, "j2");
  EXPECT_EQ(a[0].machine_id, "mill-1");
  EXPECT_EQ(a[0].attempt, 1u);
  EXPECT_EQ(a[1].job_id, "j3");
  EXPECT_EQ(a[1].machine_id, "mill-2");
  EXPECT_EQ(a[1].attempt, 3u);  // its third attempt
}

TEST(Dispatch, DeadBusyOrNotReadyMillsAreSkipped) {
  const std::vector<cell::PlannedJob> planned = {{"j1", 1, "", 0}, {"j2", 1, "", 0}};
  const std::vector<cell::MillView> mills = {{"mill-1", false, true},  // lost
                                             {"mill-2", true, false},  // running or holding
                                             {"mill-3", true, true},   // busy (below)
                                             {"mill-4", true, true}};
  const auto a = cell::choose_assignments(planned, mills, {"mill-3"});
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].job_id, "j1");
  EXPECT_EQ(a[0].machine_id, "mill-4");
}

TEST(Dispatch, APinnedJobGoesOnlyToItsMachine) {
  const std::vector<cell::PlannedJob> planned = {{"pinned", 9, "mill-2", 0}, {"free", 1, "", 0}};
  const std::vector<cell::MillView> both = {{"mill-1", true, true}, {"mill-2", true, true}};
  auto a = cell::choose_assignments(planned, both, {});
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].job_id, "pinned");
  EXPECT_EQ(a[0].machine_id, "mill-2");
  EXPECT_EQ(a[1].machine_id, "mill-1");
  // Its machine busy: the pinned job waits, the other takes mill-1.
  a = cell::choose_assignments(planned, both, {"mill-2"});
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].job_id, "free");
}

TEST(Dispatch, OneJobPerMill) {
  const std::vector<cell::PlannedJob> planned = {{"a", 1, "", 0}, {"b", 1, "", 0}};
  const auto a = cell::choose_assignments(planned, {{"mill-1", true, true}}, {});
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].job_id, "a");
}

// ---- lost edges

TEST(LostEdges, GraceCountsFromTheLossOrTheCellsStart) {
  using namespace std::chrono_literals;
  const auto t0 = std::chrono::steady_clock::time_point{} + 1h;
  const auto grace = 6000ms;
  EXPECT_FALSE(cell::edge_lost_past_grace(true, t0, t0, t0 + 1h, grace));   // alive
  EXPECT_FALSE(cell::edge_lost_past_grace(false, t0, t0, t0 + 5s, grace));  // not yet
  EXPECT_TRUE(cell::edge_lost_past_grace(false, t0, t0, t0 + 6s, grace));
  // Lost long before the cell started: the grace runs from the start.
  EXPECT_FALSE(cell::edge_lost_past_grace(false, t0 - 1h, t0, t0 + 5s, grace));
}

TEST(LostEdges, RequeuedWhileAttemptsRemainThenFailed) {
  auto n = cell::after_interruption(1, 3);
  EXPECT_TRUE(n.requeue);
  EXPECT_EQ(n.reason, "re-queued after attempt 1 of 3");
  n = cell::after_interruption(3, 3);
  EXPECT_FALSE(n.requeue);
  EXPECT_EQ(n.reason, "interrupted on every one of 3 attempts");
}
