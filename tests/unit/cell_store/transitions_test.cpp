// The job state machine, driven by scripted transitions.

#include <gmock/gmock.h>
#include <sqlite3.h>

#include <algorithm>

#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::HasSubstr;
using namespace smc::config;

class CellStoreTransitions : public StoreTest {
 protected:
  std::string queued_job(Store& s, const std::string& part = "bracket-tl") {
    smc::config::Job j;
    j.set_part_id(part);
    return s.submit_job(j).id;
  }
};

TEST_F(CellStoreTransitions, TheTableOfAllowedTransitions) {
  const std::vector<std::pair<JobState, JobState>> allowed{
      {JOB_QUEUED, JOB_PLANNED},       {JOB_PLANNED, JOB_ASSIGNED},
      {JOB_ASSIGNED, JOB_RUNNING},     {JOB_RUNNING, JOB_DONE},
      {JOB_RUNNING, JOB_FAILED},       {JOB_RUNNING, JOB_INTERRUPTED},
      {JOB_ASSIGNED, JOB_INTERRUPTED}, {JOB_INTERRUPTED, JOB_QUEUED},
      {JOB_INTERRUPTED, JOB_FAILED},   {JOB_QUEUED, JOB_FAILED},
      {JOB_PLANNED, JOB_FAILED},       {JOB_PLANNED, JOB_QUEUED}};
  int count = 0;
  for (int f = JOB_STATE_UNSPECIFIED; f <= JOB_INTERRUPTED; ++f) {
    for (int t = JOB_STATE_UNSPECIFIED; t <= JOB_INTERRUPTED; ++t) {
      const auto from = static_cast<JobState>(f), to = static_cast<JobState>(t);
      const bool expected =
          std::find(allowed.begin(), allowed.end(), std::make_pair(from, to)) != allowed.end();
      EXPECT_EQ(allowed_transition(from, to), expected)
          << state_name(from) << " -> " << state_name(to);
      count += expected ? 1 : 0;
    }
  }
  EXPECT_EQ(count, static_cast<int>(allowed.size()));
  EXPECT_TRUE(is_terminal(JOB_DONE));
  EXPECT_TRUE(is_terminal(JOB_FAILED));
  EXPECT_FALSE(is_terminal(JOB_INTERRUPTED));
  EXPECT_EQ(parse_state("Running"), JOB_RUNNING);
  EXPECT_EQ(parse_state("JOB_INTERRUPTED"), JOB_INTERRUPTED);
  EXPECT_FALSE(parse_state("paused"));
}

TEST_F(CellStoreTransitions, AJobsLifeIsPersistedWithTimesAndReasons) {
  Store s = seeded();
  const std::string id = queued_job(s);
  const std::int64_t before = s.job(id)->created_at_ms;

  SupervisorConfig plan;
  plan.set_config_id(id + "/1");
  plan.set_variant(SMC_I);
  plan.mutable_program()->set_total_depth_mm(2);
  s.set_plan(id, SMC_I, "validated force and milling models for bracket-tl on mill-1", plan);
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "two 1 mm passes"));
  ASSERT_TRUE(s.transition(id, JOB_PLANNED, JOB_ASSIGNED, "mill-1 idle", "mill-1"));
  ASSERT_TRUE(s.transition(id, JOB_ASSIGNED, JOB_RUNNING, "edge accepted configuration"));
  RunSummary result;
  result.set_completed(true);
  result.set_passes_completed(2);
  s.record_result(id, result);
  const auto done = s.transition(id, JOB_RUNNING, JOB_DONE, "program complete");
  ASSERT_TRUE(done);
  EXPECT_EQ(done->seq, 5);
  EXPECT_EQ(done->machine_id, "mill-1");

  // A fresh connection reads it all back.
  Store again = Store::open(db_path());
  const auto j = again.job(id);
  ASSERT_TRUE(j);
  EXPECT_EQ(j->state, JOB_DONE);
  EXPECT_EQ(j->machine_id, "mill-1");
  EXPECT_EQ(j->attempt, 1u);
  EXPECT_EQ(j->variant, SMC_I);
  EXPECT_THAT(j->explanation, HasSubstr("validated force and milling models"));
  ASSERT_TRUE(j->plan);
  EXPECT_EQ(j->plan->config_id(), id + "/1");
  ASSERT_TRUE(j->result);
  EXPECT_EQ(j->result->passes_completed(), 2u);
  EXPECT_GE(j->updated_at_ms, j->created_at_ms);
  // jobs() leaves the documents out unless asked.
  EXPECT_FALSE(again.jobs()[0].plan);
  EXPECT_TRUE(again.jobs({.with_documents = true})[0].plan);

  const auto ev = again.events(id);
  ASSERT_EQ(ev.size(), 5u);
  const std::vector<std::pair<JobState, JobState>> path{{JOB_STATE_UNSPECIFIED, JOB_QUEUED},
                                                        {JOB_QUEUED, JOB_PLANNED},
                                                        {JOB_PLANNED, JOB_ASSIGNED},
                                                        {JOB_ASSIGNED, JOB_RUNNING},
                                                        {JOB_RUNNING, JOB_DONE}};
  const std::vector<std::string> reasons{"submitted", "two 1 mm passes", "mill-1 idle",
                                         "edge accepted configuration", "program complete"};
  for (std::size_t i = 0; i < ev.size(); ++i) {
    EXPECT_EQ(ev[i].seq, static_cast<std::int64_t>(i + 1));
    EXPECT_EQ(ev[i].from_state, path[i].first) << i;
    EXPECT_EQ(ev[i].to_state, path[i].second) << i;
    EXPECT_EQ(ev[i].reason, reasons[i]);
    EXPECT_GE(ev[i].time_ms, before);
    if (i > 0) {
      EXPECT_GE(ev[i].time_ms, ev[i - 1].time_ms);
    }
  }
  EXPECT_EQ(ev[1].machine_id, "");
  EXPECT_EQ(ev[2].machine_id, "mill-1");
}

TEST_F(CellStoreTransitions, DisallowedTransitionsAreRefusedAndChangeNothing) {
  Store s = seeded();
  const std::string id = queued_job(s);
  const auto refused = [&](JobState from, JobState to, const std::string& machine,
                           const std::string& what) {
    try {
      s.transition(id, from, to, "test", machine);
      ADD_FAILURE() << state_name(from) << " -> " << state_name(to) << " was accepted";
    } catch (const StoreError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
      EXPECT_THAT(e.what(), HasSubstr(id));
    }
  };
  refused(JOB_QUEUED, JOB_RUNNING, "", "not an allowed transition");
  refused(JOB_QUEUED, JOB_DONE, "", "not an allowed transition");
  refused(JOB_QUEUED, JOB_QUEUED, "", "not an allowed transition");
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "planned"));
  refused(JOB_PLANNED, JOB_ASSIGNED, "", "needs the machine_id");
  refused(JOB_PLANNED, JOB_ASSIGNED, "mill-9", "unknown machine 'mill-9' (known: mill-1, mill-2)");
  refused(JOB_PLANNED, JOB_FAILED, "mill-1", "only given when assigning");
  EXPECT_EQ(s.job(id)->state, JOB_PLANNED);
  EXPECT_EQ(s.events(id).size(), 2u);
  EXPECT_THROW(s.transition("job-999999", JOB_QUEUED, JOB_PLANNED, "x"), StoreError);

  // A job that asked for a machine goes to that machine only.
  smc::config::Job pinned;
  pinned.set_part_id("bracket-tl");
  pinned.set_machine_id("mill-2");
  const std::string p = s.submit_job(pinned).id;
  ASSERT_TRUE(s.transition(p, JOB_QUEUED, JOB_PLANNED, "planned"));
  try {
    s.transition(p, JOB_PLANNED, JOB_ASSIGNED, "x", "mill-1");
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr("asks for machine 'mill-2'"));
  }
  EXPECT_TRUE(s.transition(p, JOB_PLANNED, JOB_ASSIGNED, "x", "mill-2"));

  // Done is final.
  ASSERT_TRUE(s.transition(p, JOB_ASSIGNED, JOB_RUNNING, "r"));
  ASSERT_TRUE(s.transition(p, JOB_RUNNING, JOB_DONE, "d"));
  EXPECT_THROW(s.transition(p, JOB_DONE, JOB_QUEUED, "again"), StoreError);
}

TEST_F(CellStoreTransitions, AStaleCompareAndSetFailsSoTwoDispatchersNeverRunAJobTwice) {
  { Store s = seeded(); }
  Store a = Store::open(db_path());  // dispatcher A
  Store b = Store::open(db_path());  // dispatcher B, another connection
  const std::string id = queued_job(a);
  // Both see the job queued.
  ASSERT_EQ(a.job(id)->state, JOB_QUEUED);
  ASSERT_EQ(b.job(id)->state, JOB_QUEUED);
  ASSERT_TRUE(a.transition(id, JOB_QUEUED, JOB_PLANNED, "A planned it"));
  EXPECT_FALSE(b.transition(id, JOB_QUEUED, JOB_PLANNED, "B planned it too"));
  ASSERT_TRUE(b.transition(id, JOB_PLANNED, JOB_ASSIGNED, "B assigned", "mill-2"));
  EXPECT_FALSE(a.transition(id, JOB_PLANNED, JOB_ASSIGNED, "A assigned", "mill-1"));
  const auto j = a.job(id);
  EXPECT_EQ(j->machine_id, "mill-2");
  EXPECT_EQ(j->attempt, 1u);
  const auto ev = a.events(id);
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_EQ(ev[1].reason, "A planned it");
  EXPECT_EQ(ev[2].reason, "B assigned");
}

TEST_F(CellStoreTransitions, AnInterruptedJobIsRequeuedAndCountsItsAttempts) {
  Store s = seeded();
  const std::string id = queued_job(s, "housing-js");
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "p"));
  ASSERT_TRUE(s.transition(id, JOB_PLANNED, JOB_ASSIGNED, "a", "mill-1"));
  ASSERT_TRUE(s.transition(id, JOB_ASSIGNED, JOB_RUNNING, "r"));
  ASSERT_TRUE(s.transition(id, JOB_RUNNING, JOB_INTERRUPTED, "edge mill-1 lost (liveliness)"));
  EXPECT_EQ(s.job(id)->machine_id, "mill-1");
  ASSERT_TRUE(s.transition(id, JOB_INTERRUPTED, JOB_QUEUED, "re-queued after interruption"));
  EXPECT_EQ(s.job(id)->machine_id, "");
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "p"));
  ASSERT_TRUE(s.transition(id, JOB_PLANNED, JOB_ASSIGNED, "a", "mill-2"));
  const auto j = s.job(id);
  EXPECT_EQ(j->attempt, 2u);
  EXPECT_EQ(j->machine_id, "mill-2");
  EXPECT_EQ(s.events(id).size(), 8u);
}

TEST_F(CellStoreTransitions, PlansOnlyBeforeAssignmentResultsOnlyOnceRunning) {
  Store s = seeded();
  const std::string id = queued_job(s);
  EXPECT_THROW(s.record_result(id, RunSummary{}), StoreError);
  s.set_plan(id, SMC_II, "first", SupervisorConfig{});
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "p"));
  s.set_plan(id, SMC_I, "re-planned", SupervisorConfig{});  // still planned: allowed
  ASSERT_TRUE(s.transition(id, JOB_PLANNED, JOB_ASSIGNED, "a", "mill-1"));
  try {
    s.set_plan(id, SMC_II, "too late", SupervisorConfig{});
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is assigned"));
  }
  EXPECT_EQ(s.job(id)->explanation, "re-planned");
  EXPECT_THROW(s.set_plan("job-999999", SMC_I, "x", SupervisorConfig{}), StoreError);
}

TEST_F(CellStoreTransitions, AJobThatCannotBePlannedFails) {
  Store s = seeded();
  const std::string id = queued_job(s);
  ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_FAILED, "no capable machine"));
  EXPECT_EQ(s.job(id)->state, JOB_FAILED);
  EXPECT_FALSE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "late planner"));
}

TEST_F(CellStoreTransitions, HistoryCannotBeRewritten) {
  Store s = seeded();
  const std::string id = queued_job(s);
  // Even a direct SQL edit through the same file is refused by the schema.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db_path().c_str(), &raw), SQLITE_OK);
  EXPECT_NE(sqlite3_exec(raw, "DELETE FROM job_events", nullptr, nullptr, nullptr), SQLITE_OK);
  EXPECT_NE(sqlite3_exec(raw, "UPDATE job_events SET reason = 'x'", nullptr, nullptr, nullptr),
            SQLITE_OK);
  EXPECT_NE(sqlite3_exec(raw, "DELETE FROM jobs", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
  EXPECT_EQ(s.events(id).size(), 1u);
  EXPECT_TRUE(s.job(id));
}

TEST_F(CellStoreTransitions, WritesInOneTransactionRollBackTogether) {
  Store s = seeded();
  const std::string id = queued_job(s);
  EXPECT_THROW(s.transaction([&] {
    ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "p"));
    throw std::runtime_error("planner crashed half-way");
  }),
               std::runtime_error);
  EXPECT_EQ(s.job(id)->state, JOB_QUEUED);
  EXPECT_EQ(s.events(id).size(), 1u);
}

}  // namespace
}  // namespace smc::cell::store::test
