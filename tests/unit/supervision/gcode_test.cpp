// The part program as G-code: rendered from FixedProgram and checked by
// LinuxCNC's own interpreter (rs274 -g prints the canonical machining calls
// a program makes, with no LinuxCNC running).

#include "smc/supervision/gcode.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc_config.pb.h"

namespace sv = smc::supervision;

namespace {

std::string src(const std::string& rel) { return std::string(SMC_SOURCE_DIR) + "/" + rel; }

struct Canon {
  std::string call;
  std::vector<double> args;
};

// Runs rs274 -g on the program; its canonical calls in order. rs274 comes
// with LinuxCNC (deploy/setup.sh installs linuxcnc-uspace).
std::vector<Canon> interpret(const std::string& program, std::string* error = nullptr) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-gcode-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "p.ngc";
  std::ofstream(file) << program;
  const std::string cmd = "rs274 -g " + file.string() + " 2>&1";
  std::FILE* pipe = ::popen(cmd.c_str(), "r");
  std::vector<Canon> out;
  std::string text;
  if (pipe == nullptr) return out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) text += buf;
  ::pclose(pipe);
  std::filesystem::remove_all(dir);
  if (error != nullptr) *error = text;
  const std::regex line(R"(^\s*\d+ N\.+ ([A-Z_]+)\((.*)\)\s*$)");
  std::istringstream in(text);
  std::string l;
  while (std::getline(in, l)) {
    std::smatch m;
    if (!std::regex_match(l, m, line)) continue;
    Canon c{m[1], {}};
    const std::string args = m[2];
    const std::regex number(R"(-?\d+\.\d+)");
    for (auto it = std::sregex_iterator(args.begin(), args.end(), number);
         it != std::sregex_iterator(); ++it) {
      c.args.push_back(std::stod(it->str()));
    }
    out.push_back(std::move(c));
  }
  return out;
}

sv::FixedProgram paper_program(int passes) {
  sv::FixedProgram p;
  for (int i = 0; i < passes; ++i) p.passes[p.count++] = {2.0 / passes, 10, 1500, 0};
  return p;
}

sv::CutGeometry paper_geometry() { return {4, 25, 150, 5, 0.6}; }

}  // namespace

TEST(Gcode, RequiresLinuxCncsInterpreter) {
  ASSERT_EQ(std::system("command -v rs274 >/dev/null"), 0)
      << "rs274 not found: install linuxcnc-uspace (deploy/setup.sh)";
}

// Every pass: traverse in air before the part, down to its Z level, one
// straight feed across the part at F = the highest feed the edge may
// command, retract; the adaptive feed and the feed-hold input on before the
// first cut, the spindle at speed before it, all off at the end.
TEST(Gcode, ThePapersTwoPassesAreWhatLinuxCncWouldCut) {
  const std::string text = sv::render_gcode(paper_program(2), paper_geometry(), {.title = "job-1"});
  std::string log;
  const auto calls = interpret(text, &log);
  ASSERT_FALSE(calls.empty()) << log;
  std::vector<const Canon*> feeds;
  int adaptive_on = -1, hold_on = -1, spindle_on = -1, first_feed = -1, spindle_off = -1;
  double feed_rate = 0, speed = 0;
  for (size_t i = 0; i < calls.size(); ++i) {
    const auto& c = calls[i];
    const int n = static_cast<int>(i);
    if (c.call == "ENABLE_ADAPTIVE_FEED" && adaptive_on < 0) adaptive_on = n;
    if (c.call == "ENABLE_FEED_HOLD" && hold_on < 0) hold_on = n;
    if (c.call == "START_SPINDLE_CLOCKWISE" && spindle_on < 0) spindle_on = n;
    if (c.call == "SET_SPINDLE_SPEED") speed = c.args.at(0);
    if (c.call == "SET_FEED_RATE" && !c.args.empty() && c.args[0] > 0) feed_rate = c.args[0];
    if (c.call == "STRAIGHT_FEED") {
      if (first_feed < 0) first_feed = n;
      feeds.push_back(&c);
      EXPECT_DOUBLE_EQ(feed_rate, 0.6 * 4 * 1500) << "F = max feed per tooth x teeth x rpm";
    }
    if (c.call == "STOP_SPINDLE_TURNING" && spindle_off < 0 && first_feed >= 0) spindle_off = n;
  }
  ASSERT_EQ(feeds.size(), 2u) << log;
  EXPECT_GE(adaptive_on, 0);
  EXPECT_LT(adaptive_on, first_feed);
  EXPECT_LT(hold_on, first_feed);
  EXPECT_LT(spindle_on, first_feed);
  EXPECT_DOUBLE_EQ(speed, 1500);
  EXPECT_GT(spindle_off, first_feed);
  for (int k = 0; k < 2; ++k) {
    const auto& a = feeds[static_cast<size_t>(k)]->args;
    EXPECT_DOUBLE_EQ(a.at(0), 150 + 25 + 2) << "past the part's far edge by the clearance";
    EXPECT_DOUBLE_EQ(a.at(1), 0);
    EXPECT_DOUBLE_EQ(a.at(2), -1.0 * (k + 1)) << "pass " << k;
  }
  // Each cut starts from rest in air, where the simulated mill starts it.
  for (size_t i = 1; i < calls.size(); ++i) {
    if (calls[i].call != "STRAIGHT_FEED") continue;
    const auto& before = calls[i - 1];
    ASSERT_EQ(before.call, "SET_FEED_RATE");
    const auto& traverse = calls[i - 2];
    ASSERT_EQ(traverse.call, "STRAIGHT_TRAVERSE");
    EXPECT_DOUBLE_EQ(traverse.args.at(0), -(25 + 5));
  }
  EXPECT_EQ(calls.back().call, "ON_RESET");
  EXPECT_NE(text.find("(job-1)"), std::string::npos);
}

// After module F adds a pass, the rest of the depth is what remains: the
// remainder renders passes [from, count) at their Z levels.
TEST(Gcode, ARewritesRemainderStartsAtItsOwnZLevel) {
  auto p = paper_program(1);
  ASSERT_TRUE(sv::add_one_pass(p, 0));  // 2 x 1 mm
  ASSERT_TRUE(sv::add_one_pass(p, 1));  // 1 mm + 2 x 0.5 mm
  const auto calls = interpret(sv::render_gcode(p, paper_geometry(), {.first_pass = 1}));
  std::vector<double> z;
  for (const auto& c : calls) {
    if (c.call == "STRAIGHT_FEED") z.push_back(c.args.at(2));
  }
  EXPECT_EQ(z, (std::vector<double>{-1.5, -2.0}));
}

TEST(Gcode, ThePlannedConfigurationRendersAsItsProgram) {
  const auto c = smc::documents::load_supervisor_config(src("edge/configs/smc1.textproto"));
  std::string log;
  const auto calls = interpret(sv::render_gcode(c), &log);
  int feeds = 0;
  for (const auto& cl : calls) feeds += cl.call == "STRAIGHT_FEED" ? 1 : 0;
  // (It failed once under load with no feeds at all: rs274's own words then.)
  EXPECT_EQ(feeds, c.program().passes_size()) << "rs274 -g printed:\n" << log;
}

// F never exceeds what the machine can feed: LinuxCNC would cap it at the
// axis velocity before scaling it, and the edge's scale would be wrong.
TEST(Gcode, TheMachinesMaxFeedrateCapsF) {
  auto g = paper_geometry();
  g.max_feedrate_mm_s = 36;
  double f = 0;
  for (const auto& c : interpret(sv::render_gcode(paper_program(1), g))) {
    if (c.call == "SET_FEED_RATE" && !c.args.empty() && c.args[0] > 0) f = c.args[0];
  }
  EXPECT_DOUBLE_EQ(f, 36 * 60);
}

TEST(Gcode, ImpossibleProgramsAreRefusedNamingTheField) {
  auto expect_refused = [](const sv::FixedProgram& p, const sv::CutGeometry& g,
                           const sv::GcodeOptions& o, const std::string& field) {
    try {
      (void)sv::render_gcode(p, g, o);
      ADD_FAILURE() << "rendered; expected " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  expect_refused({}, paper_geometry(), {}, "program.passes");
  auto p = paper_program(2);
  p.passes[1].depth_mm = std::nan("");
  expect_refused(p, paper_geometry(), {}, "program.passes[1].depth_mm");
  p = paper_program(2);
  p.passes[0].spindle_rpm = 0;
  expect_refused(p, paper_geometry(), {}, "program.passes[0].spindle_rpm");
  expect_refused(paper_program(2), {4, 0, 150, 5, 0.6}, {}, "cutter.radius_mm");
  expect_refused(paper_program(2), paper_geometry(), {.first_pass = 2}, "first_pass");
  // A title cannot close the comment and inject a block.
  const auto text =
      sv::render_gcode(paper_program(1), paper_geometry(), {.title = "a) G0 Z-50 (b"});
  EXPECT_EQ(text.find("G0 Z-50 ("), std::string::npos);
  for (const auto& c : interpret(text)) {
    if (c.call == "STRAIGHT_TRAVERSE") {
      EXPECT_GE(c.args.at(2), -2.0) << "no traverse below the pass's own level";
    }
  }
}
