// Process models: learnt candidates with their fit statistics, validation,
// and how find_models orders what it finds.

#include <gmock/gmock.h>

#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::HasSubstr;
using namespace smc::config;

class CellStoreModels : public StoreTest {
 protected:
  // What the learning step produces from SMC II per-revolution data.
  static ProcessModel candidate(const std::string& part) {
    ProcessModel m;
    m.kind = ModelKind::kForceProcess;
    m.machine_id = "mill-1";
    m.tool_id = "fm-r25-4t";
    m.material_id = "6061-T6";
    m.part_id = part;
    m.provenance = PROVENANCE_FITTED;
    m.validated = false;
    m.force.set_k_kn(0.74);
    m.force.set_beta(0.66);
    m.force.set_alpha(0.61);
    m.fit.set_samples(412);
    m.fit.set_r_squared(0.987);
    m.fit.set_rms_residual_n(6.5);
    m.fit.set_k_stderr(0.02);
    m.fit.set_beta_stderr(0.01);
    m.fit.set_alpha_stderr(0.015);
    m.note = "fitted from job-000002 (SMC II, per-revolution F_Y)";
    return m;
  }
};

TEST_F(CellStoreModels, AFittedCandidateRoundTripsWithItsStatistics) {
  Store s = seeded();
  const std::string id = s.add_model(candidate("housing-js"));
  EXPECT_EQ(id, "model-000001");
  Store again = Store::open(db_path());
  const auto m = again.model(id);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->kind, ModelKind::kForceProcess);
  EXPECT_EQ(m->part_id, "housing-js");
  EXPECT_EQ(m->provenance, PROVENANCE_FITTED);
  EXPECT_FALSE(m->validated);
  EXPECT_DOUBLE_EQ(m->force.k_kn(), 0.74);
  EXPECT_EQ(m->fit.samples(), 412u);
  EXPECT_DOUBLE_EQ(m->fit.r_squared(), 0.987);
  EXPECT_DOUBLE_EQ(m->fit.alpha_stderr(), 0.015);
  // The document is complete on its own.
  EXPECT_EQ(m->force.provenance(), PROVENANCE_FITTED);
  EXPECT_EQ(m->force.fit().samples(), 412u);
  EXPECT_THAT(m->note, HasSubstr("job-000002"));
  EXPECT_GT(m->created_at_ms, 0);

  // The job-shop part now has a candidate, not yet validated.
  const auto found = again.find_models("mill-1", "fm-r25-4t", "6061-T6", "housing-js");
  ASSERT_EQ(found.size(), 1u);
  EXPECT_FALSE(found[0].validated);
  again.set_model_validated(id, true);
  const auto v = again.model(id);
  EXPECT_TRUE(v->validated);
  EXPECT_TRUE(v->force.validated());
  EXPECT_EQ(again.add_model(candidate("housing-js")), "model-000002");
}

TEST_F(CellStoreModels, FindModelsOrdersPartSpecificValidatedAndIdentifiedFirst) {
  Store s = seeded();
  const std::string fitted = s.add_model(candidate("bracket-tl"));
  auto generic = candidate("");  // any part of 6061-T6
  generic.provenance = PROVENANCE_HANDBOOK;
  generic.fit.Clear();
  const std::string handbook = s.add_model(generic);
  const auto found = s.find_models("mill-1", "fm-r25-4t", "6061-T6", "bracket-tl");
  ASSERT_EQ(found.size(), 4u);
  EXPECT_TRUE(found[0].validated);  // the seeded identified models
  EXPECT_TRUE(found[1].validated);
  EXPECT_EQ(found[2].id, fitted);
  EXPECT_EQ(found[3].id, handbook);  // not for this part in particular: last
  // A model that was not fitted carries no statistics.
  EXPECT_EQ(s.model(handbook)->fit.samples(), 0u);
  EXPECT_FALSE(s.model(handbook)->force.has_fit());
}

TEST_F(CellStoreModels, BadReferencesAreNamed) {
  Store s = seeded();
  auto m = candidate("housing-js");
  m.machine_id = "mill-9";
  m.part_id = "nope";
  try {
    s.add_model(m);
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("machine_id: unknown machine 'mill-9' (known: mill-1, mill-2)"));
    EXPECT_THAT(e.what(), HasSubstr("part_id: unknown part 'nope'"));
  }
  auto dup = candidate("housing-js");
  dup.id = "bracket-tl.mill-1.force";
  EXPECT_THROW(s.add_model(dup), StoreError);
  EXPECT_EQ(s.counts().models, 4);
}

}  // namespace
}  // namespace smc::cell::store::test
