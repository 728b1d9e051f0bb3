// The edge's configuration intake (edge/src/bridge): checking happens on its
// own thread, so submitting never waits for a check, however long; the
// newest configuration wins and a superseded one is never checked.
// (Issue: a hostile configuration held up operator commands for seconds.)

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <vector>

#include "bridge.hpp"

using namespace smc::edge;
using namespace std::chrono_literals;

namespace {

struct Gate {
  std::mutex mu;
  std::condition_variable cv;
  bool open = false;
  std::vector<std::string> checked;
  void wait_open() {
    std::unique_lock lock(mu);
    cv.wait(lock, [&] { return open; });
  }
  void release() {
    {
      std::lock_guard lock(mu);
      open = true;
    }
    cv.notify_all();
  }
};

smc::config::SupervisorConfig named(const std::string& id) {
  smc::config::SupervisorConfig c;
  c.set_config_id(id);
  return c;
}

}  // namespace

TEST(ConfigIntake, SubmittingNeverWaitsForACheckAndTheNewestWins) {
  Gate gate;
  ConfigIntake intake(
      [&](const smc::config::SupervisorConfig& c) {
        {
          std::lock_guard lock(gate.mu);
          gate.checked.push_back(c.config_id());
        }
        gate.wait_open();  // a check that takes as long as the test wants
        return c.config_id() == "bad" ? std::string("refused") : std::string();
      },
      [] {});
  intake.submit(named("first"));
  // The intake thread is now inside the first check, blocked; submitting
  // more returns at once (this test would hang here otherwise).
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (true) {
    std::lock_guard lock(gate.mu);
    if (!gate.checked.empty() || std::chrono::steady_clock::now() > deadline) break;
  }
  intake.submit(named("superseded"));
  intake.submit(named("bad"));
  EXPECT_TRUE(intake.take_verdicts().empty());
  EXPECT_FALSE(intake.idle());
  gate.release();
  std::vector<std::pair<std::string, std::string>> verdicts;
  while (verdicts.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    for (auto& v : intake.take_verdicts()) verdicts.emplace_back(v.config.config_id(), v.why);
  }
  ASSERT_EQ(verdicts.size(), 2u);
  EXPECT_EQ(verdicts[0], (std::pair<std::string, std::string>{"first", ""}));
  EXPECT_EQ(verdicts[1], (std::pair<std::string, std::string>{"bad", "refused"}));
  std::lock_guard lock(gate.mu);
  EXPECT_EQ(gate.checked, (std::vector<std::string>{"first", "bad"}));  // never "superseded"
}
