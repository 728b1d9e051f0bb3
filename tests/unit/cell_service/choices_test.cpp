// The cell's choices as pure functions: SMC selection, planning, dispatch and
// the lost-edge policy, without DDS. Planning uses the shipped Grafcets,
// defaults and the paper's models from the seeded store.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include "smc/cell/candidates.hpp"
#include "smc/cell/dispatch.hpp"
#include "smc/cell/planner.hpp"
#include "smc/cell/power_plan.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc/supervision/config.hpp"
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
    store::seed_demo(*db_);
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
    return {job, part, tool, db_->find_models("mill-1", tool.id, part.material_id, part.id),
            *db_->machine("mill-1")};
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
  m.machine_id = "mill-1";
  return m;
}

// What a part's cuts showed on mill-1 at 1500 rpm: clean to `stable_mm`
// over `revolutions` at `feed` mm/tooth, chatter at 2 mm.
cell::StabilityBound cuts(double stable_mm, double feed, std::uint32_t revolutions,
                          const std::string& tool = {}) {
  cell::StabilityBound b;
  b.machine_id = "mill-1";
  b.tool_id = tool;
  b.rpm = 1500;
  b.stable_mm = stable_mm;
  b.stable_feed_mm = feed;
  b.revolutions = revolutions;
  b.chatter_mm = 2.0;
  b.jobs = {"job-1"};
  return b;
}

store::Machine mill(const std::string& id, double power_w = 745.7) {
  return store::Machine{id, "a mill", power_w, 36, 3000};
}

}  // namespace

// ---- selection

TEST(Selection, NoModelsGiveSmcII) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.tool.id = "fm";
  in.part.material_id = "al";
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("none"), std::string::npos) << sel.explanation;
  EXPECT_NE(sel.explanation.find("no validated models"), std::string::npos) << sel.explanation;
}

// The part's own cuts stand in for a structural model: a chatter-free depth
// over 20 revolutions or more, no chatter at or below it.
TEST(Selection, APartsCleanCutsStandInForAStructuralModel) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.job.spec.set_spindle_rpm(1500);
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1")};
  in.bound = cuts(1.0, 0.05, 19);
  auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II) << "19 revolutions are not enough: " << sel.explanation;
  EXPECT_NE(sel.explanation.find("no chatter-free cut of the part at 1500 rpm"), std::string::npos)
      << sel.explanation;
  in.bound->revolutions = 20;
  sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_I) << sel.explanation;
  EXPECT_FALSE(sel.milling.has_value());
  ASSERT_TRUE(sel.bound.has_value());
  EXPECT_NE(sel.explanation.find("from the part's own cuts"), std::string::npos) << sel.explanation;
  // Chatter at the clean depth: the evidence disagrees and stands for nothing.
  in.bound->chatter_mm = 1.0;
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_II);
}

TEST_F(CellChoices, APlanFromThePartsCutsKeepsToTheDepthAndFeedsItWasCutAt) {
  auto in = inputs("housing-js");
  in.bound = cuts(0.9, 0.06, 500, in.tool.id);
  in.models = {model(store::ModelKind::kForceProcess, true, "model-f")};
  in.models[0].force.set_k_kn(0.72);
  in.models[0].force.set_beta(0.65);
  in.models[0].force.set_alpha(0.63);
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_I) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  ASSERT_EQ(plan.config.program().passes_size(), 3) << "2 mm in passes of 0.9 mm at most";
  EXPECT_NEAR(plan.config.program().passes(0).depth_mm(), 2.0 / 3, 1e-9);
  EXPECT_DOUBLE_EQ(plan.config.operation().min_feed_per_tooth_mm(), 0.06)
      << "the controller's feed no lower than the clean cut's";
  EXPECT_EQ(plan.machine_id, "mill-1");
  EXPECT_EQ(plan.model_ids, std::vector<std::string>{"model-f"});
  EXPECT_EQ(plan.config.grafcet_name(), "smc1_guarded.grafcet");
  EXPECT_NE(plan.config.explanation().find("none deeper than the 0.9 mm cut without chatter"),
            std::string::npos)
      << plan.config.explanation();
  // No cutting law to plan F_ref from: module M holds the power.
  const auto sent = cell::Planner::for_machine(plan.config, in.machine, "c-1");
  for (const auto& p : sent.program().passes()) EXPECT_EQ(p.force_reference_n(), 0);
}

// A job-shop run (SMC II or SMC II+) of a part with no validated force
// model carries the identification segment, declared in its explanation;
// a part with a validated force model does not.
TEST_F(CellChoices, AJobShopRunOfAPartWithoutAForceModelCarriesAnIdentificationSegment) {
  auto in = inputs("housing-js");
  in.models.clear();
  auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_II);
  auto plan = planner_->plan(in, sel);
  ASSERT_EQ(plan.config.operation().identification_levels_size(), 2);
  EXPECT_DOUBLE_EQ(plan.config.operation().identification_levels(0), 0.6);
  EXPECT_DOUBLE_EQ(plan.config.operation().identification_levels(1), 0.8);
  EXPECT_EQ(plan.config.operation().identification_revolutions(), 15u);
  EXPECT_NE(plan.config.explanation().find("Identification segment"), std::string::npos);
  (void)smc::supervision::parameters_from_config(
      cell::Planner::for_machine(plan.config, in.machine, "c-1"));  // the edge accepts it
  auto force = model(store::ModelKind::kForceProcess, true, "model-f");
  force.part_id = "housing-js";
  in.models = {force};
  sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_II);
  plan = planner_->plan(in, sel);
  EXPECT_EQ(plan.config.operation().identification_revolutions(), 0u);
  auto plus = inputs("cover-jsp");
  plus.models.clear();
  sel = cell::select_variant(plus);
  ASSERT_EQ(sel.variant, cfg::SMC_II_PLUS);
  const auto plus_plan = planner_->plan(plus, sel);
  EXPECT_EQ(plus_plan.config.operation().identification_revolutions(), 15u);
  EXPECT_NE(plus_plan.config.explanation().find("Identification segment"), std::string::npos)
      << plus_plan.config.explanation();
}

TEST(Selection, AForceModelAloneNamesTheMissingStructuralModel) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1")};
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("no validated structural model"), std::string::npos)
      << sel.explanation;
}

TEST(Selection, BothValidatedGiveSmcIAndUnvalidatedOnesAreListedButNotUsed) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
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
  EXPECT_NE(sel.explanation.find("SMC I on mill-1"), std::string::npos) << sel.explanation;
}

TEST(Selection, AnUnvalidatedStructuralModelDoesNotMakeSmcI) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1"),
               model(store::ModelKind::kMilling, false, "model-2")};
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_II);
}

// A model a chattering SMC I cut has made suspect is listed with the reason
// but not used.
TEST(Selection, ASuspectModelIsListedWithItsReasonButNotUsed) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1"),
               model(store::ModelKind::kMilling, true, "model-2")};
  in.models[1].suspect_reason = "job-7 chattered at 612 Hz";
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_FALSE(sel.milling);
  EXPECT_NE(sel.explanation.find("suspect: job-7 chattered at 612 Hz"), std::string::npos)
      << sel.explanation;
  EXPECT_NE(sel.explanation.find("the structural model model-2 is suspect"), std::string::npos)
      << sel.explanation;
}

// Models are per machine: those of another machine never make an SMC I plan
// for this one.
TEST(Selection, AnotherMachinesModelsAreNotUsed) {
  cell::PlanInputs in;
  in.machine = mill("mill-2");
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1"),
               model(store::ModelKind::kMilling, true, "model-2")};  // on mill-1
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_II);
}

TEST(Binding, TheJobIsBoundToTheMachineWhoseModelsAllowSmcI) {
  cell::MachineModels m1{mill("mill-1"), true, {}};
  cell::MachineModels m2{mill("mill-2"), true, {}};
  for (auto* m : {&m2.models}) {
    *m = {model(store::ModelKind::kForceProcess, true, "f2"),
          model(store::ModelKind::kMilling, true, "s2")};
    for (auto& x : *m) x.machine_id = "mill-2";
  }
  cell::PlanInputs in;
  const auto sel = cell::bind_and_select(in, {m1, m2});
  EXPECT_EQ(sel.variant, cfg::SMC_I) << sel.explanation;
  EXPECT_EQ(in.machine.id, "mill-2");
  EXPECT_NE(sel.explanation.find("SMC I on mill-2"), std::string::npos) << sel.explanation;
}

TEST(Binding, AnAvailableMachineIsPreferredAmongThoseWithModels) {
  auto with_models = [](const std::string& id, bool alive) {
    cell::MachineModels m{mill(id), alive, {}};
    m.models = {model(store::ModelKind::kForceProcess, true, "f-" + id),
                model(store::ModelKind::kMilling, true, "s-" + id)};
    for (auto& x : m.models) x.machine_id = id;
    return m;
  };
  cell::PlanInputs in;
  EXPECT_EQ(cell::bind_and_select(in, {with_models("mill-1", false), with_models("mill-2", true)})
                .variant,
            cfg::SMC_I);
  EXPECT_EQ(in.machine.id, "mill-2");
  // The machine with the models is lost but another is available: the job is not
  // left waiting for it, it runs as a job-shop job on the one that is.
  cell::PlanInputs other;
  cell::MachineModels bare{mill("mill-1"), true, {}};
  const auto sel = cell::bind_and_select(other, {bare, with_models("mill-2", false)});
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_TRUE(other.machine.id.empty());
  EXPECT_NE(sel.explanation.find("mill-2: has usable models but its edge is lost"),
            std::string::npos)
      << sel.explanation;
  // None available: the first with models gets the plan and waits for it.
  cell::PlanInputs later;
  (void)cell::bind_and_select(later, {with_models("mill-1", false), with_models("mill-2", false)});
  EXPECT_EQ(later.machine.id, "mill-1");
}

TEST(Binding, WithoutModelsOnAnyMachineTheJobIsSmcIIForAnyMachine) {
  cell::MachineModels m1{
      mill("mill-1"), true, {model(store::ModelKind::kForceProcess, true, "f1")}};
  cell::MachineModels m2{mill("mill-2"), true, {}};
  cell::PlanInputs in;
  const auto sel = cell::bind_and_select(in, {m1, m2});
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_TRUE(in.machine.id.empty());
  EXPECT_NE(sel.explanation.find("f1"), std::string::npos) << sel.explanation;
  EXPECT_NE(sel.explanation.find("on any machine"), std::string::npos) << sel.explanation;
}

TEST(Binding, AJobThatNamesAMachineWithoutModelsIsSmcIIThere) {
  cell::MachineModels m1{mill("mill-1"), true, {}};
  cell::MachineModels m2{mill("mill-2"), true, {}};
  m2.models = {model(store::ModelKind::kForceProcess, true, "f2"),
               model(store::ModelKind::kMilling, true, "s2")};
  for (auto& x : m2.models) x.machine_id = "mill-2";
  cell::PlanInputs in;
  in.job.spec.set_machine_id("mill-1");
  const auto sel = cell::bind_and_select(in, {m1, m2});
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_EQ(in.machine.id, "mill-1");
  EXPECT_NE(sel.explanation.find("SMC II on mill-1"), std::string::npos) << sel.explanation;
}

// SMC II+ (beyond the paper): a job-shop part whose tolerances allow a
// spindle speed change, on a machine that can override its spindle speed.
TEST(Selection, APartAllowingASpeedChangeOnASimulatedMillIsSmcIIPlus) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.tool.id = "fm";
  in.part.id = "cover";
  in.part.material_id = "al";
  in.part.speed_change_allowed = true;
  const auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II_PLUS);
  EXPECT_NE(sel.explanation.find("SMC II+ on mill-1"), std::string::npos) << sel.explanation;
  EXPECT_NE(sel.explanation.find("allows a speed change"), std::string::npos) << sel.explanation;
  EXPECT_NE(sel.explanation.find("no validated models"), std::string::npos) << sel.explanation;
  // The LinuxCNC drive has the override (LinuxCNC's spindle override).
  in.machine.drive = "linuxcnc";
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_II_PLUS);
  // A fixed-speed spindle has nowhere to go: SMC II, saying why not II+.
  in.machine.min_spindle_rpm = in.machine.max_spindle_rpm = 1500;
  const auto fixed = cell::select_variant(in);
  EXPECT_EQ(fixed.variant, cfg::SMC_II);
  EXPECT_NE(fixed.explanation.find("Not SMC II+: mill-1's spindle has no speed range to move in"),
            std::string::npos)
      << fixed.explanation;
  // A part that does not allow it: SMC II, and II+ is not mentioned.
  in.machine = mill("mill-1");
  in.part.speed_change_allowed = false;
  const auto plain = cell::select_variant(in);
  EXPECT_EQ(plain.variant, cfg::SMC_II);
  EXPECT_EQ(plain.explanation.find("SMC II+"), std::string::npos) << plain.explanation;
}

TEST(Binding, SmcIIPlusIsBoundToAMachineThatCanChangeItsSpindleSpeed) {
  cell::MachineModels fixed{mill("mill-1"), true, {}};  // a fixed-speed spindle
  fixed.machine.min_spindle_rpm = fixed.machine.max_spindle_rpm = 1500;
  cell::MachineModels sim{mill("mill-2"), true, {}};
  cell::PlanInputs in;
  in.part.id = "cover";
  in.part.speed_change_allowed = true;
  const auto sel = cell::bind_and_select(in, {fixed, sim});
  EXPECT_EQ(sel.variant, cfg::SMC_II_PLUS);
  EXPECT_EQ(in.machine.id, "mill-2");
  // Only the fixed-speed spindle: SMC II on any machine.
  cell::PlanInputs only_fixed;
  only_fixed.part = in.part;
  EXPECT_EQ(cell::bind_and_select(only_fixed, {fixed}).variant, cfg::SMC_II);
  EXPECT_TRUE(only_fixed.machine.id.empty());
}

// A model is used only inside its validity range; the explanation says why
// not.
TEST(Selection, AModelOutsideItsValidityRangeIsNotUsed) {
  cell::PlanInputs in;
  in.machine = mill("mill-1");
  in.job.spec.set_spindle_rpm(3000);
  in.part.width_mm = 48;
  in.models = {model(store::ModelKind::kForceProcess, true, "model-1"),
               model(store::ModelKind::kMilling, true, "model-2")};
  in.models[1].validity.set_max_spindle_rpm(2000);
  auto sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("model-2 is outside its validity range (valid up to 2000 rpm, "
                                 "the job runs at 3000)"),
            std::string::npos)
      << sel.explanation;
  in.job.spec.set_spindle_rpm(1500);
  EXPECT_EQ(cell::select_variant(in).variant, cfg::SMC_I);
  in.models[0].validity.set_min_width_mm(50);
  sel = cell::select_variant(in);
  EXPECT_EQ(sel.variant, cfg::SMC_II);
  EXPECT_NE(sel.explanation.find("valid from 50 mm wide, the part is 48"), std::string::npos)
      << sel.explanation;
}

// Module E estimates the tool's vibration through the machine's structure
// (edge/CHATTER.md); a job-shop plan has no models, so the cell gives E the
// structure of the machine it is sent to, from a milling model of that
// machine with the job's tool (here the transfer-line part's, whose part
// modes the explanation says are another part's). Without one E judges the
// force spectrum alone, and the explanation says so and how to give it one.
TEST_F(CellChoices, AJobShopPlanSentToAMachineGivesModuleEThatMachinesStructure) {
  const auto in = inputs("housing-js");
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_II) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  ASSERT_EQ(plan.config.milling_model().structure().tool_y_size(), 0) << "no models planned";

  const auto structure = cell::structure_model(*db_, in.job, "mill-1");
  ASSERT_TRUE(structure.has_value());
  EXPECT_EQ(structure->id, "bracket-tl.mill-1.milling");
  const auto sent = cell::Planner::for_machine(plan.config, in.machine, "c-1", &*structure);
  const auto& st = sent.milling_model().structure();
  ASSERT_EQ(st.tool_y_size(), 1);
  EXPECT_DOUBLE_EQ(st.tool_y(0).natural_frequency_rad_s(), 4100);
  ASSERT_EQ(st.part_y_size(), 1) << "without the part's modes E reads q far too high";
  EXPECT_DOUBLE_EQ(st.part_y(0).natural_frequency_rad_s(), 2100);
  EXPECT_NE(sent.explanation().find("Module E estimates the vibration with mill-1's structure "
                                    "from model bracket-tl.mill-1.milling (handbook), the part's "
                                    "modes being part bracket-tl's"),
            std::string::npos)
      << sent.explanation();
  const auto p = smc::supervision::parameters_from_config(sent);
  EXPECT_EQ(p.vibration_mode_count, 2) << "E undoes the tool's and the part's y modes";

  // A machine the cell has no structure of: S alone, and said.
  EXPECT_FALSE(cell::structure_model(*db_, in.job, "mill-none").has_value());
  const auto bare = cell::Planner::for_machine(plan.config, in.machine, "c-2", nullptr);
  EXPECT_EQ(bare.milling_model().structure().tool_y_size(), 0);
  EXPECT_NE(bare.explanation().find("judges the force spectrum alone"), std::string::npos)
      << bare.explanation();
  EXPECT_EQ(smc::supervision::parameters_from_config(bare).vibration_mode_count, 0);
  EXPECT_EQ(cell::Planner::structure_note(plan.config, &*structure),
            "module E with the structure of model bracket-tl.mill-1.milling");
  EXPECT_NE(cell::Planner::structure_note(plan.config, nullptr).find("force spectrum alone"),
            std::string::npos);

  // An SMC I plan keeps its own model's structure, part modes and all.
  const auto tl = inputs("bracket-tl");
  const auto tl_sel = cell::select_variant(tl);
  ASSERT_EQ(tl_sel.variant, cfg::SMC_I) << tl_sel.explanation;
  const auto tl_plan = planner_->plan(tl, tl_sel);
  const auto tl_sent = cell::Planner::for_machine(tl_plan.config, tl.machine, "c-3", &*structure);
  EXPECT_EQ(tl_sent.milling_model().structure().part_y_size(), 1);
  EXPECT_EQ(tl_sent.explanation().find("Module E estimates"), std::string::npos);
  EXPECT_EQ(cell::Planner::structure_note(tl_plan.config, &*structure), "");
}

// Which model's structure E gets: one not suspect before a suspect one, the
// job's own part's before another part's.
TEST_F(CellChoices, ModuleETakesTheStructureOfTheMachinesBestModelForTheTool) {
  store::Machine m = *db_->machine("mill-1");
  m.id = "mill-structure";
  db_->put_machine(m);
  const auto in = inputs("housing-js");
  const auto milling = *cell::structure_model(*db_, in.job, "mill-1");
  auto put = [&](const std::string& id, const std::string& part, double w) {
    store::ProcessModel pm = milling;
    pm.id = id;
    pm.machine_id = m.id;
    pm.part_id = part;
    pm.milling.mutable_structure()->mutable_tool_y(0)->set_natural_frequency_rad_s(w);
    return db_->add_model(pm);
  };
  put("s-other-part", "bracket-tl", 4000);
  EXPECT_EQ(cell::structure_model(*db_, in.job, m.id)->id, "s-other-part");
  put("s-own-part", "housing-js", 3900);
  EXPECT_EQ(cell::structure_model(*db_, in.job, m.id)->id, "s-own-part");
  db_->mark_model_suspect("s-own-part", "a cut planned from it chattered");
  EXPECT_EQ(cell::structure_model(*db_, in.job, m.id)->id, "s-other-part");
  const auto best = cell::structure_model(*db_, in.job, m.id);
  const auto sent = cell::Planner::for_machine(cfg::SupervisorConfig(), m, "c-4", &*best);
  EXPECT_EQ(sent.milling_model().structure().tool_y_size(), 0) << "a plan without E gets none";
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
  // The G-code travels with the plan, rendered again for the machine: F is
  // capped by its max feedrate (36 mm/s = 2160 mm/min), not 0.6 x 4 x 1500.
  EXPECT_NE(plan.config.program().gcode().find("F3600"), std::string::npos);
  EXPECT_NE(c.program().gcode().find("F2160"), std::string::npos) << c.program().gcode();
  EXPECT_NE(c.program().gcode().find("configuration c-1 for mill-x"), std::string::npos);
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
  // Guarded by default: the chatter detector watches the SMC I cut.
  EXPECT_EQ(modules_of(plan.config), "ABCEFGIJLM");
  EXPECT_EQ(plan.config.grafcet_name(), "smc1_guarded.grafcet");
  EXPECT_EQ(plan.machine_id, "mill-1");
  EXPECT_EQ(plan.model_ids,
            (std::vector<std::string>{"bracket-tl.mill-1.force", "bracket-tl.mill-1.milling"}));
  EXPECT_TRUE(plan.config.has_force_model());
  EXPECT_NEAR(plan.config.operation().slow_period_s(), 0.04, 1e-12);  // one revolution
  EXPECT_NE(plan.config.explanation().find("2 equal passes of 1 mm"), std::string::npos)
      << plan.config.explanation();
}

TEST_F(CellChoices, NoPassIsDeeperThanTheModelsAreValidFor) {
  auto in = inputs("bracket-tl");
  for (auto& m : in.models) {
    if (m.kind == store::ModelKind::kForceProcess) m.validity.set_max_depth_mm(0.5);
  }
  const auto plan = planner_->plan(in, cell::select_variant(in));
  EXPECT_EQ(plan.config.program().passes_size(), 4) << plan.config.explanation();
  EXPECT_NE(plan.config.explanation().find("Passes no deeper than 0.5 mm"), std::string::npos)
      << plan.config.explanation();
}

// A job that names a machine retired after it was submitted is refused at
// planning, with the reason, rather than waiting for it forever.
TEST(Binding, AJobForAMachineRetiredAfterSubmissionIsRefusedAtPlanning) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-retired-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    auto db = store::Store::open((dir / "cell.db").string());
    store::seed_demo(db);
    cfg::Job spec;
    spec.set_part_id("bracket-tl");
    spec.set_machine_id("mill-2");
    const auto job = db.submit_job(spec);
    db.retire("machine", "mill-2", "ana", "sold");
    cell::Selection sel;
    try {
      (void)cell::bind_job(db, *db.job(job.id), sel);
      ADD_FAILURE() << "planned for a retired machine";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("machine 'mill-2' was retired"), std::string::npos)
          << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

// A job accepted before its tool broke (the cell retires a tool module N
// found broken) is not planned with it.
TEST(Binding, AJobWhoseToolWasRetiredAfterSubmissionIsRefusedAtPlanning) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-retired-tool-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    auto db = store::Store::open((dir / "cell.db").string());
    store::seed_demo(db);
    cfg::Job spec;
    spec.set_part_id("cover-jsp");
    const auto job = db.submit_job(spec);
    db.retire("tool", "fm-r25-4t", "cell", "broken in job job-000001 on mill-1: tool breakage");
    cell::Selection sel;
    try {
      (void)cell::bind_job(db, *db.job(job.id), sel);
      ADD_FAILURE() << "planned with a retired tool";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("tool 'fm-r25-4t' was retired"), std::string::npos)
          << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

TEST_F(CellChoices, ThePapersSmcIOnRequest) {
  cfg::SupervisorConfig defaults;
  smc::documents::load(src("cell/configs/defaults.textproto"), defaults);
  const cell::Planner paper(src("cell/grafcets"), defaults, {.guard_smc1 = false});
  const auto in = inputs("bracket-tl");
  const auto plan = paper.plan(in, cell::select_variant(in));
  EXPECT_EQ(modules_of(plan.config), "ABCIJLM");
  EXPECT_EQ(plan.config.grafcet_name(), "smc1.grafcet");
}

// The stability check covers the feeds the model-based controller commands,
// not only the programmed one: at the default lower clamp (0.005 mm/tooth)
// a 1 mm pass chatters (the critical depth falls with the feed), so the plan
// raises the clamp to the lowest feed at which it is stable.
TEST_F(CellChoices, TheLowerFeedClampIsRaisedToTheLowestStableFeed) {
  const auto in = inputs("bracket-tl");
  const auto plan = planner_->plan(in, cell::select_variant(in));
  const auto mach = smc::machining::from_proto(plan.config.milling_model(), "m");
  auto stable = [&](double fpt, double depth) {
    return smc::machining::assess_stability(mach, {1500, fpt, depth}).verdict ==
           smc::machining::Verdict::stable;
  };
  EXPECT_FALSE(stable(0.005, 1.0)) << "the default clamp would let the controller chatter";
  const double clamp = plan.config.operation().min_feed_per_tooth_mm();
  EXPECT_DOUBLE_EQ(clamp, plan.lower_clamp_mm);
  EXPECT_GT(clamp, 0.005);
  EXPECT_TRUE(stable(clamp, 1.0));
  EXPECT_FALSE(stable(0.9 * clamp, 1.0)) << "the clamp is the lowest stable feed (within 2 %)";
  EXPECT_LE(clamp, 0.8 * plan.equilibrium_feed_mm);
  // The steady feed (eq. 1 at the power-limited F_ref) keeps the margin.
  EXPECT_LT(plan.equilibrium_feed_mm, plan.programmed_feed_mm);
  EXPECT_TRUE(stable(plan.equilibrium_feed_mm, 1.0 / 0.8));
  EXPECT_NE(plan.config.explanation().find("lower clamp"), std::string::npos)
      << plan.config.explanation();
}

// A machine with less spindle power holds a lower F_ref, so L settles at a
// lower feed where the critical depth is smaller: the plan for that machine
// has more passes than the programmed feed alone would give.
TEST_F(CellChoices, ALessPowerfulMachinesLowerFeedNeedsMorePasses) {
  auto in = inputs("bracket-tl");
  const auto sel = cell::select_variant(in);
  in.machine.max_spindle_power_w = 300;
  const auto plan = planner_->plan(in, sel);
  EXPECT_GT(plan.config.program().passes_size(), 2) << plan.config.explanation();
  EXPECT_NE(plan.config.explanation().find("added for the feeds below the programmed one"),
            std::string::npos)
      << plan.config.explanation();
  const double depth = plan.config.program().passes(0).depth_mm();
  const auto mach = smc::machining::from_proto(plan.config.milling_model(), "m");
  EXPECT_EQ(
      smc::machining::assess_stability(mach, {1500, plan.equilibrium_feed_mm, depth / 0.8}).verdict,
      smc::machining::Verdict::stable);
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

TEST_F(CellChoices, TheCoverRunsUnderSmcIIPlusOnItsMachine) {
  const auto in = inputs("cover-jsp");
  const auto sel = cell::select_variant(in);
  ASSERT_EQ(sel.variant, cfg::SMC_II_PLUS) << sel.explanation;
  const auto plan = planner_->plan(in, sel);
  EXPECT_EQ(plan.machine_id, "mill-1");
  ASSERT_EQ(plan.config.program().passes_size(), 1);
  EXPECT_DOUBLE_EQ(plan.config.program().passes(0).depth_mm(), 2.0);
  EXPECT_EQ(modules_of(plan.config), "ABCDEFGHIJKMNO");
  EXPECT_EQ(plan.config.grafcet_name(), "smc2_plus.grafcet");
  EXPECT_EQ(plan.config.variant(), cfg::SMC_II_PLUS);
  // What the edge will get is a valid configuration.
  EXPECT_NO_THROW((void)smc::supervision::validate(
      cell::Planner::for_machine(plan.config, *db_->machine("mill-1"), "check")));
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
