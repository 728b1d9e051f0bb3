// Accepted jobs survive their process dying; a running Store notices jobs
// other processes submit; two processes racing to dispatch never both win.

#include <gmock/gmock.h>
#include <sys/wait.h>

#include <map>

#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::StartsWith;
using namespace smc::config;

class CellStoreDurability : public StoreTest {
 protected:
  std::vector<std::string> env(const std::string& part = "bracket-tl") const {
    return {"SMC_STORE_CHILD_DB=" + db_path(), "SMC_STORE_CHILD_PART=" + part};
  }
  static std::string accepted_id(const std::string& line) {
    EXPECT_THAT(line, StartsWith("accepted "));
    return line.size() > 9 ? line.substr(9) : std::string();
  }
};

TEST_F(CellStoreDurability, AJobAcceptedByAProcessThatExitsWithoutClosingSurvives) {
  { Store s = seeded(); }
  Child child("submit-exit", env());
  const std::string id = accepted_id(child.read_line());
  const int status = child.wait();
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  Store s = Store::open(db_path(), OpenMode::kExisting);
  const auto j = s.job(id);
  ASSERT_TRUE(j);
  EXPECT_EQ(j->state, JOB_QUEUED);
  EXPECT_EQ(s.events(id).size(), 1u);
}

TEST_F(CellStoreDurability, AJobAcceptedByAProcessKilledWithSigkillSurvives) {
  { Store s = seeded(); }
  Child child("submit-hang", env("housing-js"));
  const std::string id = accepted_id(child.read_line());  // accepted, process still alive
  child.kill_hard();
  const int status = child.wait();
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  Store s = Store::open(db_path(), OpenMode::kExisting);
  const auto j = s.job(id);
  ASSERT_TRUE(j);
  EXPECT_EQ(j->spec.part_id(), "housing-js");
  EXPECT_EQ(j->state, JOB_QUEUED);
}

TEST_F(CellStoreDurability, ARunningStoreNoticesJobsSubmittedByAnotherProcess) {
  Store service = seeded();  // the running cell's connection, open throughout
  const Job own = service.submit_job([] {
    smc::config::Job j;
    j.set_part_id("bracket-tl");
    return j;
  }());
  std::int64_t seen_version = service.data_version();
  std::int64_t seen_seq = own.seq;
  // Its own commits do not count as news.
  ASSERT_TRUE(service.transition(own.id, JOB_QUEUED, JOB_PLANNED, "p"));
  EXPECT_EQ(service.data_version(), seen_version);

  Child cli("submit-exit", env("housing-js"));  // smc-cell job submit, elsewhere
  const std::string id = accepted_id(cli.read_line());
  ASSERT_EQ(WEXITSTATUS(cli.wait()), 0);

  ASSERT_NE(service.data_version(), seen_version);
  const auto fresh = service.jobs({.state = JOB_QUEUED, .after_seq = seen_seq});
  ASSERT_EQ(fresh.size(), 1u);
  EXPECT_EQ(fresh[0].id, id);
  seen_version = service.data_version();
  seen_seq = fresh.back().seq;
  EXPECT_EQ(service.data_version(), seen_version);  // nothing new since
  EXPECT_TRUE(service.jobs({.state = JOB_QUEUED, .after_seq = seen_seq}).empty());
}

TEST_F(CellStoreDurability, TwoDispatcherProcessesNeverAssignTheSameJob) {
  constexpr int kJobs = 40;
  {
    Store s = seeded();
    for (int i = 0; i < kJobs; ++i) {
      smc::config::Job j;
      j.set_part_id(i % 2 == 0 ? "bracket-tl" : "housing-js");
      const auto id = s.submit_job(j).id;
      ASSERT_TRUE(s.transition(id, JOB_QUEUED, JOB_PLANNED, "planned"));
    }
  }
  auto e1 = env();
  e1.push_back("SMC_STORE_CHILD_MACHINE=mill-1");
  auto e2 = env();
  e2.push_back("SMC_STORE_CHILD_MACHINE=mill-2");
  Child d1("claim", e1);
  Child d2("claim", e2);
  // Both have read all the planned jobs before either moves one.
  EXPECT_EQ(d1.read_line(), "ready " + std::to_string(kJobs));
  EXPECT_EQ(d2.read_line(), "ready " + std::to_string(kJobs));
  d1.go();
  d2.go();
  std::map<std::string, std::string> winner;  // job -> machine
  const std::vector<std::pair<Child*, std::string>> dispatchers{{&d1, "mill-1"}, {&d2, "mill-2"}};
  for (const auto& [child, machine] : dispatchers) {
    for (std::string line = child->read_line(); line != "done"; line = child->read_line()) {
      ASSERT_THAT(line, StartsWith("won ")) << machine;
      const auto [it, fresh] = winner.emplace(line.substr(4), machine);
      EXPECT_TRUE(fresh) << line << " won by both dispatchers";
    }
    EXPECT_EQ(WEXITSTATUS(child->wait()), 0);
  }
  EXPECT_EQ(winner.size(), static_cast<std::size_t>(kJobs));
  Store s = Store::open(db_path());
  for (const auto& j : s.jobs()) {
    EXPECT_EQ(j.state, JOB_ASSIGNED);
    EXPECT_EQ(j.attempt, 1u);
    EXPECT_EQ(j.machine_id, winner[j.id]);
    EXPECT_EQ(s.events(j.id).size(), 3u);  // submitted, planned, assigned once
  }
}

}  // namespace
}  // namespace smc::cell::store::test
