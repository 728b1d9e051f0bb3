// LinuxCNC 2.9, headless on the shipped machine of deploy/linuxcnc/, runs
// the G-code the cell renders (services/supervision gcode.hpp). What
// happened is read from LinuxCNC's own status (deploy/linuxcnc/smc-cnc),
// not from the project's view of it. One LinuxCNC per host: the tests hold
// the "linuxcnc" resource lock and start and stop their own.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "smc/supervision/gcode.hpp"

namespace sv = smc::supervision;

namespace {

std::string src(const std::string& rel) { return std::string(SMC_SOURCE_DIR) + "/" + rel; }

// Runs a shell command; its stdout, and its exit status in *status.
std::string capture(const std::string& cmd, int* status) {
  std::FILE* p = ::popen(cmd.c_str(), "r");
  std::string out;
  if (p == nullptr) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p) != nullptr) out += buf;
  const int st = ::pclose(p);
  *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

std::vector<double> numbers_after(const std::string& json, const std::string& key) {
  std::vector<double> out;
  const std::regex re("\"" + key + R"(\":\s*(-?[0-9.]+))");
  for (auto it = std::sregex_iterator(json.begin(), json.end(), re); it != std::sregex_iterator();
       ++it) {
    out.push_back(std::stod((*it)[1]));
  }
  return out;
}

class LinuxCnc : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("smc-lcnc-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    // The mill runs as an unprivileged user: it must read the programs.
    ::chmod(dir_.c_str(), 0755);
    int st = -1;
    const std::string out =
        capture(src("deploy/linuxcnc/run.sh") + " start --dir " + (dir_ / "cnc").string(), &st);
    ASSERT_EQ(st, 0) << out;
    started_ = true;
  }
  void TearDown() override {
    if (started_) {
      int st = -1;
      const std::string out =
          capture(src("deploy/linuxcnc/run.sh") + " stop --dir " + (dir_ / "cnc").string(), &st);
      EXPECT_EQ(st, 0) << out;
    }
    std::filesystem::remove_all(dir_);
  }

  std::string write(const std::string& name, const std::string& text) {
    const auto f = dir_ / name;
    std::ofstream(f) << text;
    ::chmod(f.c_str(), 0644);
    return f.string();
  }
  // smc-cnc run FILE [ARGS], as the mill's user.
  std::string run_program(const std::string& file, const std::string& args, int* status) {
    return capture(src("deploy/linuxcnc/run.sh") + " exec " + src("deploy/linuxcnc/smc-cnc") +
                       " run " + file + " " + args,
                   status);
  }

  std::filesystem::path dir_;
  bool started_ = false;
};

}  // namespace

// Without LinuxCNC the edge's HAL side says so and what to do, and exits 2.
TEST(LinuxCncAbsent, TheEdgeNamesTheCauseAndTheFix) {
  int st = -1;
  const std::string err =
      capture(src("deploy/linuxcnc/run.sh") + " exec " + smc::test::bin_path("smc-edge") +
                  " hal-samples --count 10 --timeout 3 2>&1",
              &st);
  EXPECT_EQ(st, 2) << err;
  EXPECT_NE(err.find("is LinuxCNC running"), std::string::npos) << err;
  EXPECT_NE(err.find("deploy/linuxcnc/run.sh start"), std::string::npos) << err;
}

// Two 1 mm passes over a 20 mm part, F capped at the mill's 36 mm/s, the
// adaptive feed at 0.5: every cutting move runs at 18 mm/s by LinuxCNC's own
// velocity, and the program ends retracted with the spindle off.
TEST_F(LinuxCnc, RunsTheCellsProgramAtTheAdaptiveFeed) {
  sv::FixedProgram p;
  p.passes[p.count++] = {1, 10, 1500, 0};
  p.passes[p.count++] = {1, 10, 1500, 0};
  const sv::CutGeometry g{4, 25, 20, 5, 0.6, 36};
  const std::string file =
      write("part.ngc", sv::render_gcode(p, g, {.title = "paper part, short"}));
  int st = -1;
  const std::string json = run_program(file, "--adaptive-feed 0.5", &st);
  ASSERT_EQ(st, 0) << json;
  EXPECT_NE(json.find("\"errors\": []"), std::string::npos) << json;
  const auto v = numbers_after(json, "max_velocity_mm_s");
  ASSERT_EQ(v.size(), 2u) << json;
  for (double x : v) EXPECT_NEAR(x, 0.5 * 36, 0.01 * 18) << json;
  const std::regex final_pos(R"("final_position": \[([-0-9.]+), ([-0-9.]+), ([-0-9.]+)\])");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(json, m, final_pos)) << json;
  EXPECT_NEAR(std::stod(m[1]), 20 + 25 + 2, 1e-3);
  EXPECT_NEAR(std::stod(m[3]), 10, 1e-3);
  EXPECT_NE(json.find("\"spindle_on\": false"), std::string::npos) << json;
  // Two cuts of 77 mm at 18 mm/s at least.
  const auto d = numbers_after(json, "duration_s");
  ASSERT_EQ(d.size(), 1u);
  EXPECT_GT(d[0], 2 * 77 / 18.0);
}

// A program LinuxCNC cannot run is reported with LinuxCNC's own message, and
// the machine stays where it was.
TEST_F(LinuxCnc, AProgramThatFailsIsReportedWithLinuxCncsMessage) {
  const std::string file = write("bad.ngc", "G21 G90\nG1 X10 Y0 Z0 F\nM2\n");
  int st = -1;
  const std::string json = run_program(file, "", &st);
  EXPECT_EQ(st, 1) << json;
  EXPECT_EQ(json.find("\"errors\": []"), std::string::npos) << json;
  const std::regex final_pos(R"("final_position": \[([-0-9.]+), ([-0-9.]+), ([-0-9.]+)\])");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(json, m, final_pos)) << json;
  EXPECT_NEAR(std::stod(m[1]), 0, 1e-3) << "no motion";
}

// The edge's sampling path: LinuxCNC's stock sampler in the 2 kHz servo
// thread, read by the edge as a HAL component (smc-edge hal-samples, the
// reader the LinuxCNC drive uses), while the machine runs a program: 20,000
// records (10 s) with none lost or repeated, the axis seen moving and the
// spindle turning.
TEST_F(LinuxCnc, TheEdgeSeesEveryServoPeriodWhileTheMachineCuts) {
  sv::FixedProgram p;
  p.passes[p.count++] = {1, 10, 1500, 0};
  p.passes[p.count++] = {1, 10, 1500, 0};
  const std::string file =
      write("part.ngc", sv::render_gcode(p, {4, 25, 20, 5, 0.6, 36}, {.title = "sampling"}));
  int program_status = -1;
  std::string program_json;
  std::thread cnc(
      [&] { program_json = run_program(file, "--adaptive-feed 0.5", &program_status); });
  int st = -1;
  const std::string json =
      capture(src("deploy/linuxcnc/run.sh") + " exec " + smc::test::bin_path("smc-edge") +
                  " hal-samples --count 20000 --timeout 60",
              &st);
  cnc.join();
  EXPECT_EQ(program_status, 0) << program_json;
  ASSERT_EQ(st, 0) << json;
  EXPECT_EQ(numbers_after(json, "records"), std::vector<double>{20000}) << json;
  EXPECT_EQ(numbers_after(json, "lost"), std::vector<double>{0}) << json;
  EXPECT_EQ(numbers_after(json, "repeated"), std::vector<double>{0}) << json;
  const auto x_max = numbers_after(json, "x_max_mm");
  const auto x_min = numbers_after(json, "x_min_mm");
  ASSERT_EQ(x_max.size(), 1u);
  EXPECT_GT(x_max[0] - x_min[0], 40) << "the X axis was seen moving across the part: " << json;
  const auto revs = numbers_after(json, "spindle_revs");
  ASSERT_EQ(revs.size(), 1u);
  EXPECT_GT(revs[0], 10) << "the spindle was seen turning: " << json;
}

// The edge's outputs act on the machine: its adaptive-feed pin (linked to
// motion.adaptive-feed by smc-edge.hal) moves the path velocity to the new
// share of F, and its feed-inhibit pin stops the axis and releases it —
// every command followed, measured from LinuxCNC's own sampled velocity
// (smc-edge hal-feed-latency; the figures go to the log, the test asserts
// the behaviour: on this machine's non-realtime threads latency is noise).
TEST_F(LinuxCnc, TheEdgesFeedPinsMoveAndHoldTheAxis) {
  sv::FixedProgram p;
  p.passes[p.count++] = {1, 10, 1500, 0};
  const std::string file =
      write("long.ngc", sv::render_gcode(p, {4, 25, 400, 5, 0.6, 36}, {.title = "one long pass"}));
  int program_status = -1;
  std::string program_json;
  // Long enough for the measurement and what follows; held by the watchdog
  // at the end, it ends by its timeout.
  std::thread cnc([&] { program_json = run_program(file, "--timeout 25", &program_status); });
  int st = -1;
  const std::string json =
      capture(src("deploy/linuxcnc/run.sh") + " exec " + smc::test::bin_path("smc-edge") +
                  " hal-feed-latency --steps 10 --timeout 15",
              &st);
  struct Join {  // on every way out of the test
    std::thread& t;
    ~Join() {
      if (t.joinable()) t.join();
    }
  } join{cnc};
  std::printf("%s", json.c_str());
  ASSERT_EQ(st, 0) << json;
  EXPECT_EQ(numbers_after(json, "settled"), std::vector<double>{10}) << json;
  EXPECT_EQ(numbers_after(json, "lost"), std::vector<double>{0}) << json;
  const auto stop = numbers_after(json, "inhibit_stop_ms");
  ASSERT_EQ(stop.size(), 1u) << json;
  EXPECT_GT(stop[0], 0) << "the axis decelerates to a standstill, it does not jump";
  // The edge is gone now, the program not: its heartbeat stopped, so the
  // watchdog holds the feed (smc-edge.hal): the axis stands still while the
  // program is still in its feed move.
  int st2 = -1;
  const std::string after =
      capture(src("deploy/linuxcnc/run.sh") + " exec " + smc::test::bin_path("smc-edge") +
                  " hal-samples --count 4000 --timeout 10",
              &st2);
  ASSERT_EQ(st2, 0) << after;
  const auto v = numbers_after(after, "last_velocity_mm_s");
  ASSERT_EQ(v.size(), 1u) << after;
  EXPECT_EQ(v[0], 0) << "an edge that died leaves the machine in feed hold: " << after;
  cnc.join();
  EXPECT_NE(program_json.find("timed out"), std::string::npos)
      << "the program was held mid-pass, not ended: " << program_json;
}
