// Demo seed: idempotent, the paper's numbers, models only for the
// transfer-line part.

#include <gmock/gmock.h>
#include <google/protobuf/util/message_differencer.h>

#include <filesystem>

#include "smc/cell/store/catalog_docs.hpp"
#include "smc/documents/load.hpp"
#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::HasSubstr;

class CellStoreSeed : public StoreTest {};

TEST_F(CellStoreSeed, IsIdempotent) {
  Store s = Store::open(db_path());
  EXPECT_GT(seed_demo(s), 0);
  const Counts first = s.counts();
  EXPECT_EQ(seed_demo(s), 0);
  EXPECT_EQ(seed_demo(s, SeedOptions{default_catalog_dir()}), 0);
  const Counts again = s.counts();
  EXPECT_EQ(first.machines, 2);
  EXPECT_EQ(first.tools, 1);
  EXPECT_EQ(first.materials, 1);
  EXPECT_EQ(first.parts, 3);
  EXPECT_EQ(first.models, 4);  // force + milling for bracket-tl on each mill
  EXPECT_EQ(again.machines, first.machines);
  EXPECT_EQ(again.models, first.models);
  EXPECT_EQ(again.parts, first.parts);
}

TEST_F(CellStoreSeed, HoldsThePapersMachineToolAndMaterial) {
  Store s = seeded();
  for (const char* id : {"mill-1", "mill-2"}) {
    const auto m = s.machine(id);
    ASSERT_TRUE(m) << id;
    EXPECT_DOUBLE_EQ(m->max_spindle_power_w, 745.7);
    EXPECT_DOUBLE_EQ(m->max_feedrate_mm_s, 36);
    EXPECT_GT(m->max_spindle_rpm, 1500);
  }
  const auto t = s.tool("fm-r25-4t");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->teeth, 4u);
  EXPECT_DOUBLE_EQ(t->radius_mm, 25);
  const auto mat = s.material("6061-T6");
  ASSERT_TRUE(mat);
  EXPECT_EQ(mat->name, "6061-T6 aluminium");
  const auto bracket = s.part("bracket-tl");
  ASSERT_TRUE(bracket);
  EXPECT_EQ(bracket->material_id, "6061-T6");
  EXPECT_EQ(bracket->tool_id, "fm-r25-4t");
  EXPECT_DOUBLE_EQ(bracket->total_depth_mm, 2);
  EXPECT_DOUBLE_EQ(bracket->feedrate_mm_s, 10);
  EXPECT_DOUBLE_EQ(bracket->spindle_rpm, 1500);
  EXPECT_TRUE(s.part("housing-js"));
}

TEST_F(CellStoreSeed, TransferLinePartHasValidatedModelsJobShopPartNone) {
  Store s = seeded();
  const auto models = s.find_models("mill-1", "fm-r25-4t", "6061-T6", "bracket-tl");
  ASSERT_EQ(models.size(), 2u);
  bool force = false, milling = false;
  for (const auto& m : models) {
    EXPECT_TRUE(m.validated) << m.id;
    EXPECT_EQ(m.part_id, "bracket-tl");
    EXPECT_EQ(m.machine_id, "mill-1");
    if (m.kind == ModelKind::kForceProcess) {
      force = true;
      EXPECT_EQ(m.provenance, smc::config::PROVENANCE_IDENTIFIED);  // eq. (1), by experiment
      EXPECT_DOUBLE_EQ(m.force.k_kn(), 0.76);
      EXPECT_DOUBLE_EQ(m.force.beta(), 0.65);
      EXPECT_DOUBLE_EQ(m.force.alpha(), 0.63);
      EXPECT_TRUE(m.force.validated());
      EXPECT_EQ(m.force.provenance(), smc::config::PROVENANCE_IDENTIFIED);
    } else {
      milling = true;
      EXPECT_EQ(m.provenance, smc::config::PROVENANCE_HANDBOOK);  // the appendix's values
      EXPECT_EQ(m.milling.provenance(), smc::config::PROVENANCE_HANDBOOK);
      EXPECT_EQ(m.milling.cutter().teeth(), 4u);
      EXPECT_DOUBLE_EQ(m.milling.cutter().radius_mm(), 25);
      ASSERT_EQ(m.milling.structure().tool_x_size(), 1);
      EXPECT_DOUBLE_EQ(m.milling.structure().tool_x(0).natural_frequency_rad_s(), 4500);
      EXPECT_DOUBLE_EQ(m.milling.structure().part_y(0).damping_ratio(), 0.22);
      EXPECT_DOUBLE_EQ(m.milling.law().power_law().cutting().coefficient_kn_per_mm2(), 0.29);
      EXPECT_TRUE(m.milling.validated());
    }
  }
  EXPECT_TRUE(force && milling);
  EXPECT_EQ(s.find_models("mill-2", "", "", "bracket-tl").size(), 2u);
  EXPECT_TRUE(s.find_models("mill-1", "fm-r25-4t", "6061-T6", "housing-js").empty());
  EXPECT_TRUE(s.find_models("", "", "", "housing-js").empty());
}

TEST_F(CellStoreSeed, ModelsAreTheRepositoryDocuments) {
  // cell/catalog/models.textproto names cell/models/ for the documents: the
  // seeded models are those files, and the cutter matches the tool.
  Store s = seeded();
  smc::config::ForceProcessModel force;
  smc::documents::load(repo_file("cell/models/paper_force_model.textproto"), force);
  smc::config::MillingModel milling;
  smc::documents::load(repo_file("cell/models/paper_face_mill.textproto"), milling);
  const auto models = s.find_models("mill-1", "", "", "bracket-tl");
  ASSERT_EQ(models.size(), 2u);
  for (const auto& m : models) {
    EXPECT_TRUE(m.validated) << m.id;
    if (m.kind == ModelKind::kForceProcess) {
      EXPECT_DOUBLE_EQ(m.force.k_kn(), force.k_kn());
      EXPECT_DOUBLE_EQ(m.force.alpha(), force.alpha());
    } else {
      EXPECT_EQ(m.milling.cutter().teeth(), 4u);
      EXPECT_DOUBLE_EQ(s.tool("fm-r25-4t")->lead_angle_deg, m.milling.cutter().lead_angle_deg());
      google::protobuf::util::MessageDifferencer d;
      smc::config::MillingModel a = m.milling, b = milling;
      for (auto* x : {&a, &b}) {
        x->clear_provenance();
        x->clear_validated();
      }
      EXPECT_TRUE(d.Compare(a, b));
    }
  }
  // Every seeded entity has its history row, by "seed".
  const auto h = s.history();
  EXPECT_EQ(h.size(), 11u);  // 2 machines, 1 tool, 1 material, 3 parts, 4 models
  for (const auto& e : h) {
    EXPECT_EQ(e.author, "seed");
    EXPECT_EQ(e.action, "created");
  }
}

TEST_F(CellStoreSeed, MalformedCatalogDocumentStopsTheSeedBeforeAnyWrite) {
  for (const auto& f : std::filesystem::directory_iterator(default_catalog_dir())) {
    std::filesystem::copy_file(f.path(), dir_ / f.path().filename());
  }
  write("tools.textproto", "tools {\n  id: \"t\"\n  teeth: four\n}\n");
  Store s = Store::open(db_path());
  try {
    seed_demo(s, SeedOptions{dir_.string()});
    FAIL();
  } catch (const CatalogError& e) {
    EXPECT_THAT(e.what(), HasSubstr("tools.textproto:3:"));
  }
  const Counts c = s.counts();
  EXPECT_EQ(c.machines + c.tools + c.materials + c.parts + c.models, 0);
}

}  // namespace
}  // namespace smc::cell::store::test
