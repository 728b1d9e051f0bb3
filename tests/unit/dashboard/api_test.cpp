// The dashboard's REST API over real sockets and real DDS: state per mill
// from the live topics, documents through Protobuf's JSON mapping, operator
// commands (token required; refused ones never reach DDS), clear 4xx
// answers to bad requests.

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "dashboard_fixture.hpp"
#include "smc/wire/documents.hpp"

using namespace smc::test;
using namespace std::chrono_literals;

namespace {

const std::string kJson = "Content-Type: application/json\r\n";

std::string bearer(const std::string& token) { return "Authorization: Bearer " + token + "\r\n"; }

// Parses a JSON body with Protobuf's JSON parser (no other JSON library here).
google::protobuf::Value parse_json(const std::string& text) {
  google::protobuf::Value v;
  const auto st = google::protobuf::util::JsonStringToMessage(text, &v);
  EXPECT_TRUE(st.ok()) << st.message() << " in " << text;
  return v;
}

const google::protobuf::Value& field(const google::protobuf::Value& v, const std::string& k) {
  static const google::protobuf::Value kNull;
  const auto& f = v.struct_value().fields();
  auto it = f.find(k);
  return it == f.end() ? kNull : it->second;
}

// Every OperatorCommand the test participant takes within `timeout`.
std::vector<smc_data_OperatorCommand> take_commands(CellSide& cell, size_t at_least,
                                                    std::chrono::milliseconds timeout = 5000ms) {
  std::vector<smc_data_OperatorCommand> out;
  eventually(
      [&] {
        cell.commands.take(
            [&](const smc_data_OperatorCommand& c, const smc::transport::SampleInfo& i) {
              if (i.valid_data) out.push_back(c);
            });
        return out.size() >= at_least;
      },
      timeout);
  return out;
}

void expect_error(const HttpResponse& r, int status, const std::string& mentions) {
  EXPECT_EQ(r.status, status) << r.body;
  EXPECT_EQ(r.header("content-type"), "application/json") << r.body;
  const auto v = parse_json(r.body);
  EXPECT_EQ(field(v, "status").number_value(), status);
  EXPECT_NE(field(v, "error").string_value().find(mentions), std::string::npos)
      << "error '" << field(v, "error").string_value() << "' should mention '" << mentions << "'";
}

}  // namespace

TEST(DashboardApi, ServesHealthAndItsOwnPage) {
  DashboardFixture f;
  auto health = http(f.port(), "GET", "/api/health");
  ASSERT_EQ(health.status, 200);
  EXPECT_TRUE(field(parse_json(health.body), "ok").bool_value());
  EXPECT_EQ(field(parse_json(health.body), "operators").number_value(), 2);

  auto page = http(f.port(), "GET", "/");
  ASSERT_EQ(page.status, 200);
  EXPECT_EQ(page.header("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(page.body.find("/vendor/uPlot.iife.min.js"), std::string::npos);
  EXPECT_NE(page.header("content-security-policy").find("default-src 'self'"), std::string::npos);

  // uPlot comes from npm at build time and is served by the dashboard itself.
  auto uplot = http(f.port(), "GET", "/vendor/uPlot.iife.min.js");
  ASSERT_EQ(uplot.status, 200);
  EXPECT_EQ(uplot.header("content-type"), "text/javascript; charset=utf-8");
  EXPECT_GT(uplot.body.size(), 20000u);
  EXPECT_NE(uplot.body.find("uPlot"), std::string::npos);
  EXPECT_EQ(http(f.port(), "GET", "/app.js").status, 200);

  expect_error(http(f.port(), "GET", "/no-such-file.js"), 404, "no such page");
  expect_error(http(f.port(), "GET", "/../etc/passwd"), 404, "no such page");
}

TEST(DashboardApi, MillStateFollowsTheLiveTopicsAndDocuments) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));

  smc::config::SupervisorConfig cfg;
  cfg.set_config_id("cfg-1");
  cfg.set_variant(smc::config::SMC_II);
  cfg.set_grafcet_name("smc2");
  cfg.set_grafcet_text(read_text(std::string(SMC_SOURCE_DIR) + "/cell/grafcets/smc2.grafcet"));
  cfg.add_modules("A");
  cfg.mutable_machine()->set_max_spindle_power_w(745.7);
  cfg.set_explanation("no models: SMC II");
  f.cell().configs.publish("mill-t", "cfg-1", cfg);
  // Step index 3 is step number 4 of smc2 ("contact, no chatter"); modules A B I J.
  f.cell().situation("mill-t", 1U << 3, 0b1100000011, 1);

  ASSERT_TRUE(eventually([&] {
    auto v = parse_json(http(f.port(), "GET", "/api/mills/mill-t").body);
    const auto& steps = field(field(v, "situation"), "active_steps");
    return field(v, "config").has_struct_value() && steps.list_value().values_size() == 1 &&
           steps.list_value().values(0).number_value() == 4;
  }));
  const auto mill = parse_json(http(f.port(), "GET", "/api/mills/mill-t").body);
  EXPECT_EQ(field(field(mill, "situation"), "modules").string_value(), "ABIJ");
  EXPECT_EQ(field(field(mill, "config"), "variant").string_value(), "SMC_II");
  // The spindle power's limit, for the power chart.
  EXPECT_DOUBLE_EQ(field(field(mill, "config"), "max_spindle_power_w").number_value(), 745.7);
  EXPECT_EQ(field(field(mill, "status"), "state").string_value(), "EDGE_RUNNING");
  EXPECT_TRUE(field(mill, "online").bool_value());

  // The whole document through Protobuf's JSON mapping (proto field names).
  auto doc = http(f.port(), "GET", "/api/mills/mill-t/config");
  ASSERT_EQ(doc.status, 200);
  EXPECT_EQ(field(parse_json(doc.body), "config_id").string_value(), "cfg-1");
  EXPECT_EQ(field(parse_json(doc.body), "explanation").string_value(), "no models: SMC II");

  auto grafcet = parse_json(http(f.port(), "GET", "/api/mills/mill-t/grafcet").body);
  EXPECT_TRUE(field(grafcet, "ok").bool_value());
  EXPECT_EQ(field(grafcet, "steps").list_value().values_size(), 6);
  EXPECT_EQ(field(grafcet, "transitions").list_value().values_size(), 9);

  f.cell().summary("mill-t", 7, 201.5f);
  ASSERT_TRUE(eventually([&] {
    auto h = parse_json(http(f.port(), "GET", "/api/mills/mill-t/history?seconds=30").body);
    return field(h, "f_y_peak_n").list_value().values_size() == 1;
  }));
  auto h = parse_json(http(f.port(), "GET", "/api/mills/mill-t/history").body);
  EXPECT_EQ(field(h, "f_y_peak_n").list_value().values(0).number_value(), 201.5);
  EXPECT_EQ(field(h, "spindle_power_w").list_value().values(0).number_value(), 806.0);
  EXPECT_NEAR(field(h, "t").list_value().values(0).number_value(), 1.28, 1e-9);  // machine time

  smc::config::JobStatus job;
  job.mutable_job()->set_job_id("job-9");
  job.set_state(smc::config::JOB_RUNNING);
  job.set_variant(smc::config::SMC_II);
  job.set_machine_id("mill-t");
  job.set_explanation("no force model for part P");
  job.set_pass_count(2);
  f.cell().jobs.publish("job-9", "job-9", job);
  ASSERT_TRUE(eventually([&] {
    return parse_json(http(f.port(), "GET", "/api/jobs").body).list_value().values_size() == 1;
  }));
  const auto jobs = parse_json(http(f.port(), "GET", "/api/jobs").body);
  const auto& status = field(jobs.list_value().values(0), "status");
  EXPECT_EQ(field(status, "state").string_value(), "JOB_RUNNING");
  EXPECT_EQ(field(status, "variant").string_value(), "SMC_II");
  EXPECT_EQ(field(status, "explanation").string_value(), "no force model for part P");
  EXPECT_EQ(
      parse_json(http(f.port(), "GET", "/api/mills/mill-t/jobs").body).list_value().values_size(),
      1);
}

TEST(DashboardApi, FeedHoldWithTokenReachesDdsUnderTheOperatorsName) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));
  ASSERT_TRUE(f.cell().commands.wait_for_writers(1, 5s));
  auto r = http(f.port(), "POST", "/api/mills/mill-t/commands", R"({"action":"feed_hold_on"})",
                kJson + bearer(kBobToken));
  ASSERT_EQ(r.status, 202) << r.body;
  const auto reply = parse_json(r.body);
  EXPECT_EQ(field(reply, "operator").string_value(), "bob");
  EXPECT_TRUE(field(reply, "sent").bool_value());

  const auto cmds = take_commands(f.cell(), 1);
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_EQ(smc::wire::get_string(cmds[0].machine_id), "mill-t");
  EXPECT_EQ(cmds[0].action, static_cast<int32_t>(smc_data_OP_FEED_HOLD_ON));
  EXPECT_EQ(smc::wire::get_string(cmds[0].operator_name), "bob");
  EXPECT_EQ(std::to_string(cmds[0].command_id), field(reply, "command_id").string_value());

  // Logged: listed with who sent it.
  const auto log = parse_json(http(f.port(), "GET", "/api/commands").body);
  ASSERT_EQ(log.list_value().values_size(), 1);
  EXPECT_EQ(field(log.list_value().values(0), "operator").string_value(), "bob");
  EXPECT_EQ(field(log.list_value().values(0), "action").string_value(), "feed_hold_on");
}

TEST(DashboardApi, CommandsWithoutAValidTokenAreRefusedAndNeverReachDds) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));
  ASSERT_TRUE(f.cell().commands.wait_for_writers(1, 5s));
  const std::string body = R"({"action":"feed_hold_on"})";

  auto none = http(f.port(), "POST", "/api/mills/mill-t/commands", body, kJson);
  expect_error(none, 401, "operator token");
  EXPECT_NE(none.header("www-authenticate").find("Bearer"), std::string::npos);
  expect_error(http(f.port(), "POST", "/api/mills/mill-t/commands", body,
                    kJson + bearer("not-a-token-at-all-0000")),
               401, "unknown operator token");
  expect_error(http(f.port(), "POST", "/api/mills/mill-t/commands", body,
                    kJson + "Authorization: Basic YWxpY2U6eA==\r\n"),
               401, "unknown operator token");
  auto session = parse_json(http(f.port(), "GET", "/api/session").body);
  EXPECT_FALSE(field(session, "can_command").bool_value());
  EXPECT_EQ(http(f.port(), "GET", "/api/session", "", bearer("wrong-token-0000000000")).status,
            401);

  // A good command afterwards is the first and only one on DDS: the same
  // reliable writer would have delivered any refused one before it.
  ASSERT_EQ(http(f.port(), "POST", "/api/mills/mill-t/commands", R"({"action":"chatter_signal"})",
                 kJson + bearer(kAliceToken))
                .status,
            202);
  const auto cmds = take_commands(f.cell(), 1);
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_EQ(cmds[0].action, static_cast<int32_t>(smc_data_OP_CHATTER_SIGNAL));
  EXPECT_EQ(smc::wire::get_string(cmds[0].operator_name), "alice");
  EXPECT_EQ(parse_json(http(f.port(), "GET", "/api/commands").body).list_value().values_size(), 1);
}

TEST(DashboardApi, WithoutATokenFileTheDashboardIsReadOnly) {
  DashboardFixture f(/*tokens=*/false);
  ASSERT_TRUE(f.make_mill("mill-t"));
  expect_error(http(f.port(), "POST", "/api/mills/mill-t/commands", R"({"action":"feed_hold_on"})",
                    kJson + bearer(kAliceToken)),
               403, "read-only");
  auto session = parse_json(http(f.port(), "GET", "/api/session").body);
  EXPECT_FALSE(field(session, "commands_enabled").bool_value());
  EXPECT_EQ(http(f.port(), "GET", "/api/mills").status, 200);
}

TEST(DashboardApi, BadRequestsGetClearClientErrors) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));
  const std::string auth = bearer(kAliceToken);
  const std::string cmd = "/api/mills/mill-t/commands";

  expect_error(http(f.port(), "GET", "/api/mills/ghost"), 404, "unknown mill 'ghost'");
  expect_error(http(f.port(), "POST", "/api/mills/ghost/commands", R"({"action":"feed_hold_on"})",
                    kJson + auth),
               404, "unknown mill 'ghost'");
  expect_error(http(f.port(), "POST", cmd, R"({"action": "feed_hold_on")", kJson + auth), 400,
               "malformed JSON");
  expect_error(http(f.port(), "POST", cmd, "feed hold please", kJson + auth), 400,
               "malformed JSON");
  expect_error(http(f.port(), "POST", cmd, "{}", kJson + auth), 400, "missing 'action'");
  expect_error(http(f.port(), "POST", cmd, R"({"action":"explode"})", kJson + auth), 400,
               "unknown action 'explode'");
  expect_error(http(f.port(), "POST", cmd, R"({"action":7})", kJson + auth), 400,
               "must be a string");
  expect_error(http(f.port(), "POST", cmd, R"({"action":"feed_hold_on","force":1})", kJson + auth),
               400, "unknown field 'force'");
  expect_error(http(f.port(), "POST", cmd, R"({"action":"feed_hold_on"})",
                    "Content-Type: text/plain\r\n" + auth),
               415, "application/json");
  expect_error(http(f.port(), "POST", cmd, std::string(64 * 1024, 'x'), kJson + auth), 413,
               "larger than 4096 bytes");
  expect_error(
      http(f.port(), "GET", "/api/health", "", "X-Big: " + std::string(16 * 1024, 'y') + "\r\n"),
      431, "header larger");
  expect_error(http(f.port(), "GET", cmd), 405, "use POST");
  EXPECT_EQ(http(f.port(), "GET", cmd).header("allow"), "POST");
  expect_error(http(f.port(), "DELETE", "/api/mills"), 405, "use GET");
  expect_error(http(f.port(), "GET", "/api/nothing"), 404, "no such API resource");
  expect_error(http(f.port(), "GET", "/api/mills/mill%zz"), 400, "percent-encoding");
  expect_error(http(f.port(), "GET", "/api/mills/mill-t/history?seconds=abc"), 400, "seconds");
  expect_error(http(f.port(), "GET", "/api/stream?raw=2"), 400, "raw must be 0 or 1");
  expect_error(http(f.port(), "GET", "/api/stream?colour=red"), 400, "unknown stream parameter");
  expect_error(http(f.port(), "GET", "/api/mills/" + std::string(40, 'm')), 400, "1-31");
  expect_error(raw_request(f.port(), "HELLO THERE\r\n\r\n"), 400, "malformed HTTP request");

  // None of that put anything on DDS.
  EXPECT_TRUE(take_commands(f.cell(), 1, 300ms).empty());
}

TEST(DashboardApi, AMillWhoseEdgeIsGoneIsShownOffline) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));
  SseClient stream(f.port(), "/api/stream?mill=mill-t");
  ASSERT_TRUE(stream.next_named("hello", std::chrono::steady_clock::now() + 5s));
  f.drop_cell();
  // Statuses written while the mill was being made may still arrive first.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  std::optional<SseEvent> st;
  while ((st = stream.next_named("status", deadline)) &&
         field(parse_json(st->data), "online").bool_value()) {
  }
  ASSERT_TRUE(st) << "no status with online: false";
  const auto mill = parse_json(http(f.port(), "GET", "/api/mills/mill-t").body);
  EXPECT_FALSE(field(mill, "online").bool_value());
  EXPECT_EQ(field(field(mill, "status"), "state").string_value(), "EDGE_RUNNING");  // last known
}

// A command is volatile: one for a mill whose edge no longer reads
// commands would be lost, so the operator is told, not shown it sent.
TEST(DashboardApi, ACommandNoEdgeReadsIsRefusedAsNotDelivered) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-t"));
  f.drop_cell();  // its command reader goes with it
  ASSERT_TRUE(eventually([&] {
    const auto r = http(f.port(), "POST", "/api/mills/mill-t/commands",
                        R"({"action":"feed_hold_on"})", kJson + bearer(kBobToken));
    return r.status == 503 &&
           r.body.find("no edge of mill-t is reading operator commands") != std::string::npos;
  }));
  const auto log = parse_json(http(f.port(), "GET", "/api/commands").body);
  ASSERT_GE(log.list_value().values_size(), 1);
  EXPECT_FALSE(field(log.list_value().values(0), "sent").bool_value());
  EXPECT_NE(field(log.list_value().values(0), "error").string_value().find("not delivered"),
            std::string::npos);
}

TEST(DashboardApi, KeepAliveConnectionsServeSeveralRequests) {
  DashboardFixture f;
  Socket s(f.port());
  std::string in;
  for (int i = 0; i < 3; ++i) {
    s.send_all("GET /api/health HTTP/1.1\r\nHost: x\r\n\r\n");
    HttpResponse r;
    size_t head = 0;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while ((head = parse_head(in, r)) == 0 ||
           in.size() < head + std::stoul(r.header("content-length"))) {
      ASSERT_TRUE(s.read_some(in, deadline)) << "request " << i;
    }
    EXPECT_EQ(r.status, 200);
    in.erase(0, head + std::stoul(r.header("content-length")));
  }
}

// The cell's catalog, read-only: machines (joined with their live state by
// the page) and, per part, the SMC a job would get and why.
TEST(DashboardApi, ShowsTheCellsCatalogAndItsChoices) {
  DashboardFixture f;
  EXPECT_TRUE(
      field(parse_json(http(f.port(), "GET", "/api/catalog").body), "view").has_null_value())
      << "no catalog before the cell sends one";
  smc::wire::DocumentPublisher<smc::config::CatalogView> catalogs(f.cell().participant);
  smc::config::CatalogView view;
  auto* m = view.mutable_catalog()->add_machines();
  m->set_id("mill-c");
  m->set_max_spindle_power_w(745.7);
  m->set_drive("linuxcnc");
  view.mutable_catalog()->add_parts()->set_id("bracket-tl");
  auto* choice = view.add_parts();
  choice->set_part_id("bracket-tl");
  choice->set_variant(smc::config::SMC_I);
  choice->set_machine_id("mill-c");
  choice->set_explanation("models on mill-c ...: SMC I on mill-c (transfer line)");
  choice->add_model_ids("bracket-tl.mill-c.force");
  auto* note = view.add_machine_notes();
  note->set_machine_id("mill-c");
  note->set_model_id("mill-c.tap");
  note->set_text("module E's wideband channel (2 kHz ...) takes the structure's y mode ...");
  catalogs.publish("cell", "catalog", view);
  ASSERT_TRUE(eventually([&] {
    return field(parse_json(http(f.port(), "GET", "/api/catalog").body), "view").has_struct_value();
  }));
  const auto v = field(parse_json(http(f.port(), "GET", "/api/catalog").body), "view");
  const auto& machines = field(field(v, "catalog"), "machines").list_value();
  ASSERT_EQ(machines.values_size(), 1);
  EXPECT_EQ(field(machines.values(0), "drive").string_value(), "linuxcnc");
  const auto& parts = field(v, "parts").list_value();
  ASSERT_EQ(parts.values_size(), 1);
  EXPECT_EQ(field(parts.values(0), "variant").string_value(), "SMC_I");
  EXPECT_EQ(field(parts.values(0), "machine_id").string_value(), "mill-c");
  EXPECT_NE(field(parts.values(0), "explanation").string_value().find("SMC I on mill-c"),
            std::string::npos);
  const auto& notes = field(v, "machine_notes").list_value();
  ASSERT_EQ(notes.values_size(), 1) << "a machine's channel warning, for the page";
  EXPECT_EQ(field(notes.values(0), "machine_id").string_value(), "mill-c");
  EXPECT_EQ(field(notes.values(0), "model_id").string_value(), "mill-c.tap");
  EXPECT_EQ(http(f.port(), "POST", "/api/catalog").status, 405) << "read-only";
}
