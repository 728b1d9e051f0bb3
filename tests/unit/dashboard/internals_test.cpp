// The dashboard's parts without sockets: operator tokens, the Grafcet view
// (step indices -> numbers), the JSON writer, the per-mill state.

#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "auth.hpp"
#include "cell_state.hpp"
#include "grafcet_view.hpp"
#include "http_target.hpp"
#include "json.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

using smc::dashboard::Auth;

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(Auth, ParsesNameTokenLinesAndAuthenticatesBearerTokens) {
  const Auth a = Auth::parse("# operators\n\nalice  0123456789abcdefXYZ\n bob fedcba9876543210 \n",
                             "tokens.txt");
  EXPECT_TRUE(a.enabled());
  EXPECT_EQ(a.size(), 2u);
  EXPECT_EQ(a.authenticate("Bearer 0123456789abcdefXYZ").value_or(""), "alice");
  EXPECT_EQ(a.authenticate("bearer fedcba9876543210").value_or(""), "bob");
  EXPECT_FALSE(a.authenticate("Bearer 0123456789abcdefXY"));    // a prefix
  EXPECT_FALSE(a.authenticate("Bearer 0123456789abcdefXYZZ"));  // longer
  EXPECT_FALSE(a.authenticate("0123456789abcdefXYZ"));          // no scheme
  EXPECT_FALSE(a.authenticate("Basic 0123456789abcdefXYZ"));
  EXPECT_FALSE(a.authenticate(""));
  EXPECT_FALSE(Auth().enabled());
  EXPECT_FALSE(Auth().authenticate("Bearer 0123456789abcdefXYZ"));
}

TEST(Auth, ReportsEveryBadLineWithItsPlace) {
  try {
    Auth::parse(
        "alice short\nbob\nalice 0123456789abcdef\ncarol 0123456789abcdef\nbad/name "
        "0123456789abcdefgh\n",
        "tokens.txt");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("tokens.txt:1: token of 'alice' must be at least 16"), std::string::npos)
        << what;
    EXPECT_NE(what.find("tokens.txt:2: expected 'NAME TOKEN'"), std::string::npos) << what;
    EXPECT_NE(what.find("tokens.txt:4: token of 'carol' is also the token of 'alice'"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("tokens.txt:5: operator name 'bad/name'"), std::string::npos) << what;
  }
}

// The file holds SHA-256 hashes (the values here from sha256sum, not from
// the code under test); a token in clear still works, and is named.
TEST(Auth, StoresTokensAsTheirSha256AndNamesTheOnesInClear) {
  EXPECT_EQ(Auth::hash_line("alice", "0123456789abcdefXYZ"),
            "alice sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea");
  const Auth a = Auth::parse(
      "alice sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea\n"
      "bob SHA256:3465F6E6975BAA864CA957F0914ECDA9BF7EB601AC31AC20A5DC3D329279A843\n"
      "carol carol-in-clear-0123456789\n",
      "tokens.txt");
  EXPECT_EQ(a.size(), 3u);
  EXPECT_EQ(a.authenticate("Bearer 0123456789abcdefXYZ").value_or(""), "alice");
  EXPECT_EQ(a.authenticate("Bearer carol-in-clear-0123456789").value_or(""), "carol");
  EXPECT_EQ(a.in_clear(), std::vector<std::string>{"carol"});
  // The hash itself is not a token.
  EXPECT_FALSE(a.authenticate(
      "Bearer sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea"));
  EXPECT_EQ(a.authenticate("Bearer fedcba9876543210").value_or(""), "bob");  // upper case hex
  EXPECT_THROW(Auth::hash_line("bad/name", "0123456789abcdefXYZ"), std::invalid_argument);
  EXPECT_THROW(Auth::hash_line("alice", "short"), std::invalid_argument);
}

TEST(Auth, ABadHashOrAHashOfAnotherOperatorsTokenIsAnErrorNamingItsLine) {
  try {
    Auth::parse(
        "alice sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46ee\n"
        "bob sha256:zz9dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea\n"
        "carol 0123456789abcdefXYZ\n"
        "dave sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea\n",
        "tokens.txt");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("tokens.txt:1: token hash of 'alice' must be 'sha256:' and 64 hex"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("tokens.txt:2: token hash of 'bob'"), std::string::npos) << what;
    EXPECT_NE(what.find("tokens.txt:4: token of 'dave' is also the token of 'carol'"),
              std::string::npos)
        << what;
  }
}

TEST(GrafcetView, MapsStepIndicesToTheDesignersNumbers) {
  const auto text = read_text(std::string(SMC_SOURCE_DIR) + "/cell/grafcets/smc2.grafcet");
  const auto v = smc::dashboard::make_grafcet_view(text, "smc2.grafcet");
  ASSERT_TRUE(v.ok) << v.json;
  EXPECT_EQ(v.step_numbers, (std::vector<uint32_t>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(v.input_names, (std::vector<std::string>{"a", "b", "c", "d", "e"}));
  EXPECT_EQ(smc::dashboard::active_step_numbers(v, 0b10000), (std::vector<uint32_t>{5}));
  EXPECT_EQ(smc::dashboard::active_step_numbers(v, 1ULL << 40), (std::vector<uint32_t>{0}));
  EXPECT_NE(v.json.find(R"("number":4,"label":"contact, no chatter")"), std::string::npos);
  EXPECT_NE(v.json.find(R"({"number":6,"from":[4],"to":[6],"receptivity":"↑c + ↑d"})"),
            std::string::npos)
      << v.json;
  EXPECT_NE(v.json.find(R"({"name":"E","impulse":true})"), std::string::npos);
}

TEST(GrafcetView, ABrokenGrafcetGivesItsErrorsNotAHalfModel) {
  const auto v = smc::dashboard::make_grafcet_view("step 1 initial\ntransition 1: 1 -> 9 whn a\n",
                                                   "smc_config/mill-1");
  EXPECT_FALSE(v.ok);
  EXPECT_TRUE(v.step_numbers.empty());
  EXPECT_NE(v.json.find(R"("ok":false,"errors":["smc_config/mill-1:2:)"), std::string::npos)
      << v.json;
}

TEST(JsonWriter, EscapesAndSeparates) {
  smc::dashboard::JsonWriter w;
  w.begin_object()
      .field("s", "a\"b\\c\nd\x01")
      .field("f", 0.1f)
      .field("d", 2.5)
      .field("n", -3)
      .field("b", true)
      .key("nan")
      .value(std::numeric_limits<double>::quiet_NaN())
      .key("l")
      .begin_array()
      .value(1)
      .value(2)
      .end_array()
      .key("r")
      .raw("{\"x\":1}")
      .end_object();
  EXPECT_EQ(
      w.str(),
      R"({"s":"a\"b\\c\nd\u0001","f":0.1,"d":2.5,"n":-3,"b":true,"nan":null,"l":[1,2],"r":{"x":1}})");
}

TEST(CellState, SituationsBeforeTheirConfigAreRenderedAgainWithStepNumbers) {
  smc::dashboard::CellState state;
  smc_data_SupervisorSituation s{};
  smc::wire::set_string(s.machine_id, "m1");
  s.active_steps = 1U << 3;
  s.modules_active = 1U << 2;  // C: feed hold
  auto ev = state.on_situation(s, 0);
  ASSERT_EQ(ev.size(), 2u);  // a new mill, then its situation
  EXPECT_EQ(ev[0].kind, smc::dashboard::EventKind::kMill);
  EXPECT_NE(ev[1].frame->find(R"("active_steps":null)"), std::string::npos) << *ev[1].frame;
  EXPECT_NE(ev[1].frame->find(R"("feed_hold":true)"), std::string::npos);

  smc::config::SupervisorConfig c;
  c.set_config_id("c1");
  c.set_grafcet_text(read_text(std::string(SMC_SOURCE_DIR) + "/cell/grafcets/smc2.grafcet"));
  ev = state.on_config("m1", c);
  EXPECT_TRUE(ev.empty());  // published, not yet in force
  smc_data_EdgeStatus st{};
  smc::wire::set_string(st.machine_id, "m1");
  smc::wire::set_string(st.config_id, "c1");
  ev = state.on_status(st);
  ASSERT_EQ(ev.size(), 3u);  // the status, the configuration in force, the situation again
  EXPECT_EQ(ev[1].kind, smc::dashboard::EventKind::kConfig);
  EXPECT_EQ(ev[2].kind, smc::dashboard::EventKind::kSituation);
  EXPECT_NE(ev[2].frame->find(R"("active_steps":[4])"), std::string::npos) << *ev[2].frame;
  EXPECT_EQ(ev[2].frame->rfind("event: situation\ndata: {", 0), 0u);
  EXPECT_EQ(ev[2].frame->substr(ev[2].frame->size() - 2), "\n\n");
}

TEST(CellState, ARefusedConfigurationIsShownApartFromTheOneInForce) {
  smc::dashboard::CellState state;
  smc::config::SupervisorConfig good, bad;
  good.set_config_id("good");
  good.set_grafcet_text(read_text(std::string(SMC_SOURCE_DIR) + "/cell/grafcets/smc2.grafcet"));
  bad.set_config_id("bad");
  bad.set_grafcet_text("garbage");
  smc_data_EdgeStatus st{};
  smc::wire::set_string(st.machine_id, "m1");
  smc::wire::set_string(st.config_id, "good");
  // The edge reports the good one in force before its document reaches us.
  (void)state.on_status(st);
  (void)state.on_config("m1", good);
  ASSERT_TRUE(state.config_json("m1").has_value());
  EXPECT_NE(state.config_json("m1")->find("good"), std::string::npos);
  // The cell publishes a bad one; the edge refuses it and keeps the good one.
  (void)state.on_config("m1", bad);
  const std::string reason(600, 'r');
  smc::wire::set_string(st.refused_config_id, "bad");
  smc::wire::set_string(st.refusal, reason);
  (void)state.on_status(st);
  const auto cfg = state.config_json("m1");
  ASSERT_TRUE(cfg.has_value());
  EXPECT_NE(cfg->find("\"good\""), std::string::npos) << *cfg;
  EXPECT_EQ(cfg->find("\"bad\""), std::string::npos) << *cfg;
  const auto mill = state.mill_json("m1");
  ASSERT_TRUE(mill.has_value());
  EXPECT_NE(mill->find(R"("refused_config_id":"bad")"), std::string::npos) << *mill;
  EXPECT_NE(mill->find(reason), std::string::npos) << "the whole reason, not cut at 90";
}

TEST(CellState, ForgetsFinishedJobsFirstPastTheLimit) {
  smc::dashboard::StateLimits limits;
  limits.jobs = 3;
  smc::dashboard::CellState state(limits);
  smc::config::JobStatus j;
  j.set_state(smc::config::JOB_DONE);
  state.on_job("done-1", j);
  j.set_state(smc::config::JOB_RUNNING);
  state.on_job("run-1", j);
  state.on_job("run-2", j);
  state.on_job("run-3", j);
  const auto jobs = state.jobs_json();
  EXPECT_EQ(jobs.find("done-1"), std::string::npos) << jobs;
  EXPECT_NE(jobs.find("run-1"), std::string::npos);
  EXPECT_NE(jobs.find("run-3"), std::string::npos);
}

TEST(CellState, AChatterEventDeliveredAgainCountsOnce) {
  // A reconnection (cut link, restarted dashboard) makes the edge's
  // transient-local writer deliver its events again.
  smc::dashboard::CellState state;
  smc_data_ChatterEvent e{};
  smc::wire::set_string(e.machine_id, "m1");
  e.event_id = 42;
  e.source = smc_data_CHATTER_AUTOMATIC;
  auto first = state.on_chatter(e);
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first.back().kind, smc::dashboard::EventKind::kChatter);
  EXPECT_TRUE(state.on_chatter(e).empty()) << "a repeat must not be streamed again";
  e.event_id = 43;
  EXPECT_FALSE(state.on_chatter(e).empty());
  const auto mill = state.mill_json("m1");
  ASSERT_TRUE(mill.has_value());
  EXPECT_NE(mill->find(R"("chatter_events":2)"), std::string::npos) << *mill;
}

// Found by fuzz_http: a raw NUL (or any control character) in the request
// target passed through into the path segments. It is refused now; escapes
// still decode, %00 is still refused.
TEST(HttpTarget, RawControlCharactersAreRefused) {
  using smc::dashboard::parse_target;
  EXPECT_FALSE(parse_target(std::string_view("/api/a\0b", 8)).has_value());
  EXPECT_FALSE(parse_target("/api/a\nb").has_value());
  EXPECT_FALSE(parse_target("/api/mills?x=\x7f").has_value());
  EXPECT_FALSE(parse_target("/api/a%00b").has_value());
  const auto t = parse_target("/api/mills/mill%2D1?x=a+b&y=%41");
  ASSERT_TRUE(t.has_value());
  ASSERT_EQ(t->segments.size(), 3u);
  EXPECT_EQ(t->segments[2], "mill-1");
  ASSERT_EQ(t->query.size(), 2u);
  EXPECT_EQ(t->query[0].second, "a b");
  EXPECT_EQ(t->query[1].second, "A");
}
