// LinuxCNC 2.9, headless on the shipped machine of deploy/linuxcnc/, runs
// the G-code the cell renders (services/supervision gcode.hpp). What
// happened is read from LinuxCNC's own status (deploy/linuxcnc/smc-cnc),
// not from the project's view of it. One LinuxCNC per host: the tests hold
// the "linuxcnc" resource lock and start and stop their own.

#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/model.hpp"
#include "smc/supervision/gcode.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace sv = smc::supervision;
namespace store = smc::cell::store;
namespace cfg = smc::config;

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

// Joins a thread on every way out of a test (an ASSERT returns early).
struct JoinOnExit {
  std::thread& t;
  ~JoinOnExit() {
    if (t.joinable()) t.join();
  }
};

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
  JoinOnExit join{cnc};
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

// ---------------------------------------------------------------------------
// The cell on LinuxCNC: LinuxCNC headless with the virtual dynamometer (the
// paper's mill and part), the cell service, and one edge with --drive
// linuxcnc, run as the mill's user. The paper's transfer-line job (SMC I)
// and a job-shop job on a part of the same geometry (SMC II) run to the end.
// What happened is read from LinuxCNC's own status (smc-cnc watch), and the
// figures are compared with smc-edge simulate on the configuration the cell
// sent.

namespace {

// One row of smc-cnc watch.
struct Watch {
  double t_s = 0;
  std::string file;
  int line = 0, motion_type = 0;
  double x = 0, z = 0, v = 0, adaptive = 0;
  bool inhibit = false;
  int interp = 0;
};

std::vector<Watch> read_watch(const std::string& path) {
  std::vector<Watch> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    Watch w;
    char file[256] = {};
    int inhibit = 0;
    if (std::sscanf(line.c_str(), "%lf,%255[^,],%d,%d,%lf,%lf,%lf,%lf,%d,%d", &w.t_s, file, &w.line,
                    &w.motion_type, &w.x, &w.z, &w.v, &w.adaptive, &inhibit, &w.interp) == 10) {
      w.file = file;
      w.inhibit = inhibit != 0;
      rows.push_back(w);
    } else if (std::sscanf(line.c_str(), "%lf,,%d,%d,%lf,%lf,%lf,%lf,%d,%d", &w.t_s, &w.line,
                           &w.motion_type, &w.x, &w.z, &w.v, &w.adaptive, &inhibit,
                           &w.interp) == 9) {
      w.inhibit = inhibit != 0;
      rows.push_back(w);
    }
  }
  return rows;
}

// A CSV line's fields.
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> f;
  std::size_t from = 0;
  for (std::size_t at; (at = line.find(',', from)) != std::string::npos; from = at + 1) {
    f.push_back(line.substr(from, at - from));
  }
  f.push_back(line.substr(from));
  return f;
}

// A CSV file (the run's samples.csv or revolutions.csv) read row by row,
// its columns found by their header's names. A missing column is a test
// failure naming the file and the header, and the table then has no rows.
class CsvTable {
 public:
  CsvTable(const std::string& path, std::initializer_list<const char*> names) : in_(path) {
    std::string line;
    std::getline(in_, line);
    const std::vector<std::string> header = csv_fields(line);
    for (const char* name : names) {
      const auto it = std::find(header.begin(), header.end(), name);
      if (it == header.end()) {
        ADD_FAILURE() << path << ": no " << name << " column in '" << line << "'";
        columns_.clear();
        return;
      }
      columns_.push_back(static_cast<std::size_t>(it - header.begin()));
      needed_ = std::max(needed_, columns_.back() + 1);
    }
  }
  // The next row's fields, in the order of the names asked; false at the end.
  bool next(std::vector<std::string>& out) {
    if (columns_.empty()) return false;
    std::string line;
    while (std::getline(in_, line)) {
      const std::vector<std::string> f = csv_fields(line);
      if (f.size() < needed_) continue;
      out.clear();
      for (std::size_t c : columns_) out.push_back(f[c]);
      return true;
    }
    return false;
  }

 private:
  std::ifstream in_;
  std::vector<std::size_t> columns_;
  std::size_t needed_ = 0;
};

// The position of the cutter's axis (mm) in the last revolution of a run's
// revolutions.csv in contact with F_Y above `force_n`: where its cut ended.
double last_cutting_x(const std::string& path, double force_n) {
  CsvTable table(path, {"x_mm", "f_y_peak_n", "contact"});
  double last = -1;
  for (std::vector<std::string> r; table.next(r);) {
    if (std::atof(r[1].c_str()) > force_n && r[2] == "1") last = std::atof(r[0].c_str());
  }
  return last;
}

// The lowest spindle speed (rpm) of a run's samples.csv from `from_s` until
// the cutter's axis has moved 0.05 mm from where it stood then: while a
// rewrite hands the remainder over, with the tool where the chatter left it.
double slowest_spindle_until_moved(const std::string& path, double from_s) {
  CsvTable table(path, {"t_s", "x_mm", "spindle_rpm"});
  double x0 = std::nan(""), slowest = HUGE_VAL;
  for (std::vector<std::string> r; table.next(r);) {
    if (std::atof(r[0].c_str()) < from_s) continue;
    const double x = std::atof(r[1].c_str());
    if (std::isnan(x0)) x0 = x;
    if (std::fabs(x - x0) > 0.05) break;
    slowest = std::min(slowest, std::atof(r[2].c_str()));
  }
  return slowest;
}

// Revolutions in contact in which module E judged its vibration estimate
// (a chatter_vibration_ratio above 0), and the median of that q over them.
struct EstimateSeen {
  int revolutions = 0;
  double median_q = 0;
};
EstimateSeen estimate_seen(const std::string& path) {
  CsvTable table(path, {"chatter_vibration_ratio", "contact"});
  std::vector<double> q;
  for (std::vector<std::string> r; table.next(r);) {
    const double v = std::atof(r[0].c_str());
    if (r[1] == "1" && v > 0) q.push_back(v);
  }
  if (q.empty()) return {};
  std::nth_element(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(q.size() / 2), q.end());
  return {static_cast<int>(q.size()), q[q.size() / 2]};
}

// Samples in contact; those of them whose tool vibration (vibration_y_mm:
// what the chatter label reads) is known, and known and not 0 (as written,
// to 1 nm).
struct VibrationSeen {
  int in_contact = 0, known = 0, nonzero = 0;
};
VibrationSeen vibration_seen(const std::string& path) {
  CsvTable table(path, {"vibration_y_mm", "contact"});
  VibrationSeen seen;
  for (std::vector<std::string> r; table.next(r);) {
    if (r[1] != "1") continue;
    ++seen.in_contact;
    const double v = std::strtod(r[0].c_str(), nullptr);
    if (std::isfinite(v)) ++seen.known;
    if (std::isfinite(v) && v != 0) ++seen.nonzero;
  }
  return seen;
}

double monotonic_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The Z levels at which a program's feed moves crossed the whole part, by
// LinuxCNC's own position.
std::vector<double> full_passes(const std::vector<Watch>& rows, const std::string& file_prefix,
                                double x_from, double x_to) {
  std::map<long, std::pair<double, double>> span;  // z in µm -> x range
  for (const auto& r : rows) {
    if (r.motion_type != 2 || r.file.rfind(file_prefix, 0) != 0) continue;
    auto& s = span.try_emplace(std::lround(r.z * 1000), 1e9, -1e9).first->second;
    s.first = std::min(s.first, r.x);
    s.second = std::max(s.second, r.x);
  }
  std::vector<double> out;
  for (const auto& [z, s] : span) {
    if (s.first <= x_from && s.second >= x_to) out.push_back(static_cast<double>(z) / 1000);
  }
  std::sort(out.begin(), out.end());
  return out;
}

class LinuxCncCell : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* uri = std::getenv("CYCLONEDDS_URI");
    ASSERT_NE(uri, nullptr) << "the tests' DDS profile (loopback only) must be set";
    uri_ = uri;
    partition_ = smc::test::unique_partition("lcnc");
    dir_ = std::filesystem::temp_directory_path() / partition_;
    std::filesystem::create_directories(dir_ / "programs");
    // The mill's user writes the programs and the watch file here.
    ::chmod(dir_.c_str(), 0777);
    ::chmod((dir_ / "programs").c_str(), 0777);
    db_ = (dir_ / "cell.db").string();
    int st = -1;
    std::string out =
        capture(src("deploy/linuxcnc/run.sh") + " start --dir " + (dir_ / "cnc").string() +
                    " --dyno " + src("edge/configs/smc2.textproto"),
                &st);
    ASSERT_EQ(st, 0) << out;
    started_ = true;
    out = capture(bin("smc-cell") + " db init --seed --db " + db_ + " 2>&1", &st);
    ASSERT_EQ(st, 0) << out;
    // A job-shop part of the paper's geometry (the dynamometer's blank):
    // no models, so SMC II.
    const std::string part = (dir_ / "part.textproto").string();
    std::ofstream(part) << "parts { id: \"housing-150\" name: \"housing, 150 mm (no models)\" "
                           "material_id: \"6061-T6\" tool_id: \"fm-r25-4t\" width_mm: 48 "
                           "offset_mm: 0 length_mm: 150 total_depth_mm: 2 feedrate_mm_s: 10 "
                           "spindle_rpm: 1500 }\n";
    out = capture(bin("smc-cell") + " catalog apply " + part + " --db " + db_ +
                      " --author test --reason 'a job-shop part of the blank on LinuxCNC' 2>&1",
                  &st);
    ASSERT_EQ(st, 0) << out;
    cell_.emplace(std::vector<std::string>{bin("smc-cell"), "--log-level", "warn", "serve", "--db",
                                           db_, "--partition", partition_, "--edge-grace-ms",
                                           "1500"});
    watch_.emplace(std::vector<std::string>{src("deploy/linuxcnc/run.sh"), "exec",
                                            src("deploy/linuxcnc/smc-cnc"), "watch", "--out",
                                            watch_file()});
    edge_.emplace(std::vector<std::string>{
        src("deploy/linuxcnc/run.sh"), "exec", "env", "CYCLONEDDS_URI=" + uri_, bin("smc-edge"),
        "--log-level", "info", "run", "--machine", "mill-1", "--drive", "linuxcnc", "--partition",
        partition_, "--lease-ms", "1000", "--no-realtime", "--program-dir",
        (dir_ / "programs").string()});
  }
  void TearDown() override {
    // The mill's user's processes stop on SIGTERM (runuser passes it on).
    for (auto* p : {&edge_, &watch_}) {
      if (*p) {
        (*p)->kill(SIGTERM);
        (*p)->wait();
        p->reset();
      }
    }
    cell_.reset();
    if (started_) {
      int st = -1;
      const std::string out =
          capture(src("deploy/linuxcnc/run.sh") + " stop --dir " + (dir_ / "cnc").string(), &st);
      EXPECT_EQ(st, 0) << out;
    }
    // A failed run keeps its folder (LinuxCNC's logs under cnc/, the
    // watch's status rows, the programs handed over) for whoever reads it.
    if (HasFailure()) {
      std::fprintf(stderr, "the run's folder is kept: %s\n", dir_.c_str());
    } else {
      std::filesystem::remove_all(dir_);
    }
  }

  static std::string bin(const std::string& name) { return smc::test::bin_path(name); }
  std::string watch_file() const { return (dir_ / "watch.csv").string(); }

  std::string submit(const std::string& file) {
    const auto before = jobs();
    int st = -1;
    const std::string out = capture(
        bin("smc-cell") + " --log-level warn job submit " + file + " --db " + db_ + " 2>&1", &st);
    EXPECT_EQ(st, 0) << out;
    for (const auto& j : jobs()) {
      bool known = false;
      for (const auto& b : before) known = known || b.id == j.id;
      if (!known) return j.id;
    }
    return {};
  }
  std::vector<store::Job> jobs() {
    auto db = store::Store::open(db_, store::OpenMode::kExisting);
    return db.jobs({.with_documents = true});
  }
  store::Job job(const std::string& id) {
    auto db = store::Store::open(db_, store::OpenMode::kExisting);
    return *db.job(id);
  }
  bool wait_state(const std::string& id, cfg::JobState state, std::chrono::seconds limit) {
    const auto until = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < until) {
      const auto j = job(id);
      if (j.state == state) return true;
      if (store::is_terminal(j.state)) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  }
  // The job's events, for messages.
  std::string history(const std::string& id) {
    auto db = store::Store::open(db_, store::OpenMode::kExisting);
    std::string out;
    for (const auto& e : db.events(id)) out += e.reason + "\n";
    return out;
  }

  std::string uri_, partition_, db_;
  std::filesystem::path dir_;
  bool started_ = false;
  std::optional<smc::test::ChildProcess> cell_, watch_, edge_;
};

}  // namespace

TEST_F(LinuxCncCell, ThePapersJobsRunOnLinuxCncAsOnTheSimulatedMill) {
  using namespace std::chrono_literals;
  namespace tr = smc::transport;
  tr::Participant participant({.partition = partition_});
  tr::Topic<smc_data_OperatorCommand> topic(participant);
  tr::Writer<smc_data_OperatorCommand> commands(topic, "mill-1");
  auto command = [&](int32_t action, uint64_t id) {
    smc_data_OperatorCommand c{};
    smc::wire::set_string(c.machine_id, "mill-1");
    smc::wire::set_string(c.operator_name, "test");
    c.command_id = id;
    c.action = action;
    commands.write(c);
  };

  // 1. The transfer-line job (SMC I); mid-cut, an operator feed hold for 1 s.
  const std::string tl = submit(src("cell/jobs/transfer_line.textproto"));
  ASSERT_FALSE(tl.empty());
  ASSERT_TRUE(wait_state(tl, cfg::JOB_RUNNING, 60s)) << history(tl);
  ASSERT_TRUE(commands.wait_for_readers(1, std::chrono::seconds(10))) << "the edge's reader";
  double t_hold = 0, v_hold = 0;
  for (const auto until = std::chrono::steady_clock::now() + 60s;
       t_hold == 0 && std::chrono::steady_clock::now() < until;) {
    const auto rows = read_watch(watch_file());
    // In the first pass's feed move, well inside the part, at speed.
    if (!rows.empty() && rows.back().motion_type == 2 && rows.back().x > 40 && rows.back().v > 3 &&
        !rows.back().inhibit) {
      t_hold = monotonic_s();
      v_hold = rows.back().v;
      command(smc_data_OP_FEED_HOLD_ON, 1);
    } else {
      std::this_thread::sleep_for(20ms);
    }
  }
  ASSERT_GT(t_hold, 0) << "the first pass never reached X40";
  std::this_thread::sleep_for(1s);
  command(smc_data_OP_FEED_HOLD_OFF, 2);
  ASSERT_TRUE(wait_state(tl, cfg::JOB_DONE, 150s)) << history(tl);

  // 2. The job-shop job (SMC II): chatter, a rewritten program.
  const std::string js_file = (dir_ / "job_shop.textproto").string();
  std::ofstream(js_file) << "part_id: \"housing-150\" material: \"6061-T6\" tool_id: "
                            "\"fm-r25-4t\" depth_mm: 2 feedrate_mm_s: 10 spindle_rpm: 1500\n";
  const std::string js = submit(js_file);
  ASSERT_FALSE(js.empty());
  ASSERT_TRUE(wait_state(js, cfg::JOB_DONE, 180s)) << history(js);
  std::this_thread::sleep_for(200ms);  // the watch's last lines
  watch_->kill(SIGTERM);
  watch_->wait();
  watch_.reset();
  const auto rows = read_watch(watch_file());
  ASSERT_GT(rows.size(), 1000u);

  const store::Job a = job(tl), b = job(js);
  EXPECT_EQ(a.variant, cfg::SMC_I) << a.explanation;
  EXPECT_EQ(b.variant, cfg::SMC_II) << b.explanation;
  ASSERT_TRUE(a.result && b.result && a.plan && b.plan);

  // From LinuxCNC's status: SMC I cut its two planned passes across the
  // part (X from before the part to past its end) at Z-1 and Z-2.
  // The drive names each program <machine>-<configuration>-r<revision>-p<pass>.
  const std::string prog_a = "mill-1-" + a.id + "-a1-r";
  const std::string prog_b = "mill-1-" + b.id + "-a1-r";
  EXPECT_EQ(full_passes(rows, prog_a + "0-p1", -20, 170), (std::vector<double>{-2, -1}));
  // SMC II: the rewritten program (revision 1, from pass 1) ran both of its
  // passes across the part; the original one-pass program did not finish.
  EXPECT_EQ(full_passes(rows, prog_b + "1-p1", -20, 170), (std::vector<double>{-2, -1}))
      << "LinuxCNC completes the rewritten program in two passes";
  EXPECT_TRUE(full_passes(rows, prog_b + "0-p1", -20, 170).empty());
  EXPECT_GE(b.result->chatter_events(), 1u);
  EXPECT_EQ(b.result->passes_completed(), 2u);
  EXPECT_EQ(rows.back().interp, 1) << "LinuxCNC ended idle";

  // The operator's feed hold: LinuxCNC's feed-inhibit, then standstill,
  // within one 10 ms module period, LinuxCNC's deceleration (v / 500 mm/s²)
  // and 20 ms for DDS, the edge's comms thread and this watch's 1 ms polls.
  double t_inhibit = -1, t_stop = -1;
  for (const auto& r : rows) {
    if (r.t_s < t_hold) continue;
    if (t_inhibit < 0 && r.inhibit) t_inhibit = r.t_s;
    if (t_inhibit >= 0 && t_stop < 0 && r.v < 1e-3) t_stop = r.t_s;
  }
  ASSERT_GE(t_inhibit, 0) << "the hold reached motion.feed-inhibit";
  ASSERT_GE(t_stop, 0) << "the axis stopped";
  const double bound = 0.010 + v_hold / 500.0 + 0.020;
  std::printf(
      "feed hold: inhibit after %.1f ms, standstill after %.1f ms from %.2f mm/s "
      "(bound %.1f ms)\n",
      (t_inhibit - t_hold) * 1e3, (t_stop - t_hold) * 1e3, v_hold, bound * 1e3);
  EXPECT_LE(t_stop - t_hold, bound);

  // The axis velocity follows the adaptive feed: in feed moves, not held,
  // with the adaptive feed steady over the last 40 ms (the acceleration
  // limit takes up to 36 mm/s / 500 mm/s² = 72 ms for a full step; the
  // controller's steps are far smaller), velocity = adaptive x 36 mm/s.
  std::vector<double> err;
  for (std::size_t i = 0, j = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    while (rows[j].t_s < r.t_s - 0.040) ++j;
    if (r.motion_type != 2 || r.inhibit || r.adaptive <= 0.05) continue;
    bool steady = true;
    for (std::size_t k = j; k <= i && steady; ++k) {
      steady = rows[k].motion_type == 2 && !rows[k].inhibit &&
               std::fabs(rows[k].adaptive - r.adaptive) < 0.01;
    }
    if (steady) err.push_back(std::fabs(r.v - r.adaptive * 36.0));
  }
  ASSERT_GT(err.size(), 1000u) << "steady feed samples";
  std::sort(err.begin(), err.end());
  const double p50 = err[err.size() / 2], p95 = err[err.size() * 95 / 100];
  std::printf("velocity - adaptive feed x 36 mm/s: p50 %.3f, p95 %.3f mm/s over %zu samples\n", p50,
              p95, err.size());
  EXPECT_LT(p50, 0.1);
  EXPECT_LT(p95, 0.5);

  // The figures agree with smc-edge simulate on the configuration the cell
  // sent (smc-cell job show --config) and the dynamometer's mill:
  //  - passes and chatter events: equal;
  //  - peak force: within 5 % of F_ref without chatter. With chatter the
  //    peak is reached while chatter grows, and LinuxCNC's hold decelerates
  //    (10 mm/s at 500 mm/s²: 20 ms, half a revolution) where the simulated
  //    mill stops at once, so LinuxCNC's peak is the higher: up to 15 % of
  //    F_ref above the simulated mill's, at most 10 % below it (five runs on
  //    the paper's SMC II job: 281.6-292.1 N against 273.7 N, +4 to +10 %;
  //    the 10 % this bound was first is too tight);
  //  - cycle time: LinuxCNC's is longer by what the simulated mill
  //    idealises: its program starts the spindle and approaches the part
  //    at the axes' acceleration limits (up to 6 s), and each rewrite adds a
  //    stop, an abort, a retract, a new spindle start and approach (up to
  //    4 s); the cuts themselves take the same time.
  for (const store::Job* j : {&a, &b}) {
    const std::string cfg_file = (dir_ / (j->id + ".textproto")).string();
    int st = -1;
    const std::string sent =
        capture(bin("smc-cell") + " job show " + j->id + " --config --db " + db_, &st);
    ASSERT_EQ(st, 0) << sent;
    std::ofstream(cfg_file) << sent;
    const std::string out_dir = (dir_ / (j->id + "-sim")).string();
    // The dynamometer's mill: the paper's (run.sh start --dyno smc2.textproto).
    const std::string out =
        capture(bin("smc-edge") + " simulate --quiet --config " + cfg_file + " --mill-model " +
                    src("cell/models/paper_face_mill.textproto") + " --out " + out_dir + " 2>&1",
                &st);
    ASSERT_EQ(st, 0) << out;
    cfg::RunSummary sim;
    smc::documents::load(out_dir + "/summary.json", sim);
    const auto& lc = *j->result;
    std::printf(
        "%s %s: LinuxCNC / simulate: passes %u / %u, chatter %u / %u, peak F %.1f / "
        "%.1f N (F_ref %.1f), cycle %.1f / %.1f s\n",
        j->id.c_str(), cfg::SmcVariant_Name(j->variant).c_str(), lc.passes_completed(),
        sim.passes_completed(), lc.chatter_events(), sim.chatter_events(), lc.peak_force_n(),
        sim.peak_force_n(), sim.force_reference_n(), lc.cycle_time_s(), sim.cycle_time_s());
    EXPECT_EQ(lc.passes_completed(), sim.passes_completed());
    EXPECT_EQ(lc.chatter_events(), sim.chatter_events());
    const bool chatter = sim.chatter_events() > 0;
    EXPECT_LE(lc.peak_force_n() - sim.peak_force_n(),
              (chatter ? 0.15 : 0.05) * sim.force_reference_n());
    EXPECT_GE(lc.peak_force_n() - sim.peak_force_n(),
              -(chatter ? 0.10 : 0.05) * sim.force_reference_n());
    const double extra = lc.cycle_time_s() - sim.cycle_time_s();
    EXPECT_GE(extra, 0.0);
    EXPECT_LE(extra, 6.0 + 4.0 * sim.program_rewrites());
  }
}

// ---------------------------------------------------------------------------
// Faults on LinuxCNC: each names its cause, leaves the machine in feed hold
// (never moving under an adaptive feed nobody supervises) and ends the run.
// The runs are smc-edge simulate --drive linuxcnc on the paper's job-shop
// configuration, cut by the virtual dynamometer.

namespace {

class LinuxCncDyno : public LinuxCnc {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("smc-lcnf-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    ::chmod(dir_.c_str(), 0777);
    int st = -1;
    const std::string out =
        capture(src("deploy/linuxcnc/run.sh") + " start --dir " + (dir_ / "cnc").string() +
                    " --dyno " + src("edge/configs/smc2.textproto"),
                &st);
    ASSERT_EQ(st, 0) << out;
    started_ = true;
  }
  // A command as the mill's user; its output (stdout and stderr).
  std::string as_mill(const std::string& cmd, int* status) {
    return capture(src("deploy/linuxcnc/run.sh") + " exec " + cmd + " 2>&1", status);
  }
  std::string simulate(const std::string& config, const std::string& name, int* status,
                       int max_time_s = 40) {
    return as_mill(smc::test::bin_path("smc-edge") +
                       " simulate --quiet --drive linuxcnc --config " + config + " --max-time " +
                       std::to_string(max_time_s) + " --out " + (dir_ / name).string() +
                       " --program-dir " + (dir_ / "programs").string(),
                   status);
  }
  double pin(const std::string& name) {
    int st = -1;
    const std::string v = as_mill("halcmd getp " + name, &st);
    if (v.rfind("TRUE", 0) == 0) return 1;
    if (v.rfind("FALSE", 0) == 0) return 0;
    return std::atof(v.c_str());
  }
  // smc-edge simulate on LinuxCNC in its own thread, for tests that act on
  // the mill while it cuts; joined when it goes out of scope.
  struct Run {
    std::thread thread;
    std::atomic<bool> ended{false};
    std::string out;
    int status = -1;
    void join() {
      if (thread.joinable()) thread.join();
    }
    ~Run() { join(); }
  };
  std::unique_ptr<Run> start_run(const std::string& config, const std::string& name,
                                 int max_time_s) {
    auto r = std::make_unique<Run>();
    r->thread = std::thread([this, r = r.get(), config, name, max_time_s] {
      r->out = simulate(src(config), name, &r->status, max_time_s);
      r->ended = true;
    });
    return r;
  }
  // Until the dynamometer cuts (a tooth in the part), up to 20 s. A run that
  // ends first fails it with its status and output (a fault before the cut,
  // e.g. a false breakage at the entry, would otherwise read as a time-out).
  ::testing::AssertionResult cutting(Run& r) {
    for (int i = 0; i < 200; ++i) {
      if (pin("smc-dyno.teeth-in-cut") > 0) return ::testing::AssertionSuccess();
      if (r.ended) {
        r.join();
        return ::testing::AssertionFailure()
               << "the run ended (status " << r.status << ") before a tooth was seen in the part:\n"
               << r.out;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return ::testing::AssertionFailure() << "no tooth in the part after 20 s";
  }
  void python(const std::string& code) {
    int st = -1;
    const std::string out = as_mill(
        "python3 -c 'import linuxcnc; c = linuxcnc.command(); " + code + "; c.wait_complete(5)'",
        &st);
    ASSERT_EQ(st, 0) << out;
  }
};

}  // namespace

// E-stop in the cut: the run ends naming it, the feed stays held, and a run
// started in E-stop is refused before anything moves.
TEST_F(LinuxCncDyno, EStopMidCutEndsTheRunNamingItAndAJobInEStopIsRefused) {
  const auto run = start_run("edge/configs/smc2.textproto", "estop", 40);
  ASSERT_TRUE(cutting(*run));
  python("c.state(linuxcnc.STATE_ESTOP)");
  run->join();
  EXPECT_EQ(run->status, 4) << run->out;
  EXPECT_NE(run->out.find("E-stop"), std::string::npos) << run->out;
  EXPECT_NE(run->out.find("the feed is held"), std::string::npos) << run->out;
  EXPECT_EQ(pin("motion.current-vel"), 0.0);
  int st2 = -1;
  const std::string again = simulate(src("edge/configs/smc2.textproto"), "estop2", &st2);
  EXPECT_EQ(st2, 2) << again;
  EXPECT_NE(again.find("LinuxCNC is in E-stop"), std::string::npos) << again;
}

// The servo records stop (the sampler taken out of the servo thread): within
// 50 ms the drive holds the feed, LinuxCNC's program is aborted, the run ends
// naming the cause.
TEST_F(LinuxCncDyno, StaleServoRecordsHoldTheFeedAndEndTheRun) {
  const auto run = start_run("edge/configs/smc2.textproto", "stale", 40);
  ASSERT_TRUE(cutting(*run));
  int hs = -1;
  const std::string h = as_mill("halcmd delf sampler.0 servo-thread", &hs);
  ASSERT_EQ(hs, 0) << h;
  run->join();
  EXPECT_EQ(run->status, 4) << run->out;
  EXPECT_NE(run->out.find("servo records stopped"), std::string::npos) << run->out;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(pin("motion.current-vel"), 0.0) << "stopped, program aborted";
}

// NaN on a force pin mid-cut: the core's non-finite-force fault holds the
// feed; LinuxCNC's axis stands still while the run waits for an operator.
TEST_F(LinuxCncDyno, ANaNForceHoldsTheFeedOnLinuxCnc) {
  const auto run = start_run("edge/configs/smc2.textproto", "nan", 10);
  ASSERT_TRUE(cutting(*run));
  int hs = -1;
  std::string h = as_mill("halcmd unlinkp smc-dyno.force-z", &hs);
  ASSERT_EQ(hs, 0) << h;
  h = as_mill("halcmd sets smc-force-z nan", &hs);
  ASSERT_EQ(hs, 0) << h;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(pin("motion.feed-inhibit"), 1.0);
  EXPECT_EQ(pin("motion.current-vel"), 0.0) << "held in the cut";
  run->join();  // held until --max-time
  EXPECT_EQ(run->status, 3) << run->out;
  std::ifstream summary((dir_ / "nan" / "summary.json").string());
  const std::string json((std::istreambuf_iterator<char>(summary)), {});
  EXPECT_NE(json.find("non-finite force sample"), std::string::npos) << json;
}

// A program LinuxCNC refuses (a part longer than the X axis's travel): the
// run ends with LinuxCNC's own message, and nothing moved along X.
TEST_F(LinuxCncDyno, AProgramLinuxCncRefusesEndsTheRunWithItsMessage) {
  auto c = smc::documents::load_supervisor_config(src("edge/configs/smc2.textproto"));
  c.mutable_milling_model()->mutable_workpiece()->set_length_mm(600);  // X travel ends at 500
  const std::string file = write("long_part.textproto", smc::documents::to_textproto(c));
  int st = -1;
  const std::string out = simulate(file, "refused", &st);
  EXPECT_NE(st, 0) << out;
  EXPECT_NE(out.find("LinuxCNC"), std::string::npos) << out;
  EXPECT_NE(out.find("limit"), std::string::npos) << "LinuxCNC's reason: " << out;
  EXPECT_LT(pin("joint.0.pos-fb"), 1.0) << "X never went into the part";
}

// SMC II+ on LinuxCNC: the paper's chatter moves the spindle through
// LinuxCNC's own spindle override (module O), not by an added pass, and the
// 2 mm pass is cut at full depth at the new speed. The override stays in
// LinuxCNC after the job; the next job starts at 1.
TEST_F(LinuxCncDyno, ASpeedChangeThroughTheSpindleOverrideSuppressesThePapersChatter) {
  auto override_now = [&] {
    int st = -1;
    const std::string v = as_mill(
        "python3 -c 'import linuxcnc; s = linuxcnc.stat(); s.poll(); "
        "print(s.spindle[0][\"override\"])'",
        &st);
    EXPECT_EQ(st, 0) << v;
    return std::atof(v.c_str());
  };
  int st = -1;
  const std::string out = simulate(src("edge/configs/smc2_plus.textproto"), "plus", &st, 90);
  ASSERT_EQ(st, 0) << out;
  std::ifstream summary((dir_ / "plus" / "summary.json").string());
  const std::string json((std::istreambuf_iterator<char>(summary)), {});
  EXPECT_NE(json.find("\"completed\": true"), std::string::npos) << json;
  EXPECT_EQ(numbers_after(json, "spindle_speed_changes"), std::vector<double>{1}) << json;
  EXPECT_EQ(numbers_after(json, "program_rewrites"), std::vector<double>{0}) << json;
  EXPECT_EQ(numbers_after(json, "passes_completed"), std::vector<double>{1}) << json;
  // Tlusty and Smith's speed with the 4 % margin for the ~750 Hz chatter E
  // measured: 2700 rpm for 750 Hz on the simulated mill; here what E measured
  // on LinuxCNC's motion, within the machine's 3000 rpm.
  const auto rpm = numbers_after(json, "final_spindle_rpm");
  ASSERT_EQ(rpm.size(), 1u) << json;
  EXPECT_GT(rpm[0], 2500) << json;
  EXPECT_LE(rpm[0], 3000) << json;
  EXPECT_NEAR(override_now(), rpm[0] / 1500.0, 0.01) << "LinuxCNC's own override";
  const auto cycle = numbers_after(json, "cycle_time_s");
  const auto detected = numbers_after(json, "chatter_detected_s");
  std::printf(
      "SMC II+ on LinuxCNC: chatter detected at %.2f s, spindle to %.0f rpm, cycle %.1f s\n",
      detected.empty() ? -1.0 : detected[0], rpm[0], cycle.empty() ? -1.0 : cycle[0]);
  // The next job starts with no override (a short run of it is enough).
  int st2 = -1;
  const std::string next = simulate(src("edge/configs/smc2.textproto"), "next", &st2, 2);
  EXPECT_EQ(st2, 3) << "stopped by --max-time: " << next;
  EXPECT_NEAR(override_now(), 1.0, 1e-9);
}

// Module N on LinuxCNC: a tooth breaks in the steady cut (the dynamometer's
// break-tooth pin) under SMC II+; N stops the feed, the drive lifts the tool
// to the safe Z, the run ends with the tool broken (exit status 5), and
// LinuxCNC's axes stand still.
TEST_F(LinuxCncDyno, ABrokenToothStopsTheFeedAndLiftsTheToolOnLinuxCnc) {
  // Into the steady cut, before the paper's chatter (detected about 4.4 s
  // after first contact here): the dynamometer breaks the tooth 1.5 s of
  // the machine's own time after the first tooth met the part. (Set from
  // the test 1.5 s of the wall clock after it saw the first tooth, the
  // break could land anywhere under load: CI once saw a run with neither
  // chatter nor a break found in 28 s of cut.)
  int hs = -1;
  std::string h = as_mill("halcmd setp smc-dyno.break-after-s 1.5", &hs);
  ASSERT_EQ(hs, 0) << h;
  h = as_mill("halcmd setp smc-dyno.break-tooth 2", &hs);
  ASSERT_EQ(hs, 0) << h;
  const auto run = start_run("edge/configs/smc2_plus.textproto", "broken", 30);
  ASSERT_TRUE(cutting(*run));
  const double z_cut = pin("joint.2.pos-fb");
  run->join();
  EXPECT_EQ(run->status, 5) << "the tool broke: " << run->out;
  EXPECT_NE(run->out.find("the tool broke"), std::string::npos) << run->out;
  // The drive lifted the tool clear: LinuxCNC's program aborted, a rapid to
  // the programs' safe Z (10 mm above the part's top) in MDI.
  EXPECT_LT(z_cut, 0.0) << "the tool was in the part";
  EXPECT_NEAR(pin("joint.2.pos-fb"), 10.0, 0.01) << run->out;
  EXPECT_EQ(pin("smc-dyno.teeth-in-cut"), 0.0) << "clear of the part";
  EXPECT_NE(run->out.find("LinuxCNC lifted it"), std::string::npos) << run->out;
  EXPECT_EQ(pin("motion.current-vel"), 0.0) << "the axis stands still";
  std::ifstream summary((dir_ / "broken" / "summary.json").string());
  const std::string json((std::istreambuf_iterator<char>(summary)), {});
  EXPECT_EQ(numbers_after(json, "chatter_events"), std::vector<double>{0}) << json;
  const auto broken = numbers_after(json, "tool_broken_s");
  ASSERT_EQ(broken.size(), 1u) << json;
  // The break N found is the one the pin made, 1.5 s into the cut, not a
  // false one at the entry.
  const auto contact = numbers_after(json, "contact_s");
  ASSERT_EQ(contact.size(), 1u) << json;
  EXPECT_GT(broken[0], contact[0] + 1.0) << json;
}

// The real-time path on LinuxCNC never allocates: the core with the
// LinuxCNC drive runs the paper's job-shop cut (contact, force control,
// chatter, the rewrite's hand-over; under SMC II+ the speed change's) under
// an allocation guard, as LinuxCNC's user (smc-linuxcnc-rt-probe).
TEST_F(LinuxCncDyno, TheLoopOnLinuxCncNeverAllocates) {
  // The probe's JSON for a configuration run for some seconds.
  auto probe = [&](const std::string& config, int seconds, int* st) {
    const std::string json =
        as_mill(smc::test::bin_path("smc-linuxcnc-rt-probe") + " " + src("edge/configs/" + config) +
                    " " + std::to_string(seconds) + " " + (dir_ / "programs").string(),
                st);
    std::printf("%s", json.c_str());
    return json;
  };
  int st = -1;
  const std::string json = probe("smc2.textproto", 14, &st);
  ASSERT_EQ(st, 0) << json;
  EXPECT_EQ(numbers_after(json, "ticks"), std::vector<double>{28000}) << json;
  EXPECT_EQ(numbers_after(json, "allocations"), std::vector<double>{0}) << json;
  EXPECT_EQ(numbers_after(json, "rewrites"), std::vector<double>{1})
      << "the guard covered a rewrite: " << json;
  EXPECT_EQ(numbers_after(json, "lost"), std::vector<double>{0}) << json;
  // SMC II+: the chatter's speed change goes through the same hand-over
  // (LinuxCNC's spindle override), under the same guard.
  const std::string plus = probe("smc2_plus.textproto", 10, &st);
  ASSERT_EQ(st, 0) << plus;
  EXPECT_EQ(numbers_after(plus, "allocations"), std::vector<double>{0}) << plus;
  EXPECT_EQ(numbers_after(plus, "rewrites"), std::vector<double>{1}) << "a speed change: " << plus;
  // The second job on this LinuxCNC cuts a fresh blank (the first left the
  // tool in its part): no material missing under the cutter, which N read
  // as a broken tooth before the dynamometer waited for the tool to clear.
  EXPECT_EQ(numbers_after(plus, "tool_broken"), std::vector<double>{0}) << plus;
  const auto rpm = numbers_after(plus, "rpm");
  ASSERT_EQ(rpm.size(), 1u) << plus;
  EXPECT_GT(rpm[0], 2500) << "the spindle moved to the new pocket: " << plus;
}

// A stable cut with runout on the dynamometer: 3000 rpm, 25 mm wide, 10 um
// of eccentric runout, 5.5 mm deep (0.3 x the critical depth at 0.1
// mm/tooth). The detector study labels it stable; runout puts S, F_z's
// non-harmonic share, above S-alone's 0.3 (its entry on the simulated mill:
// 0.357), while E's vibration estimate reads it as the repeating cut it is.
class LinuxCncRunout : public LinuxCncDyno {
 protected:
  void SetUp() override { start(1); }
  // The wideband channel sampled `wide_per_tick` times a servo period by
  // the dynamometer, and expected so by E: 5 is the shipped configuration's
  // (10 kHz, an eighth order at 3.5 kHz), 1 the paper's rate (a second order
  // at 500 Hz, a quarter of it), with E's rules for each rate.
  void start(int wide_per_tick) {
    dir_ = std::filesystem::temp_directory_path() / ("smc-lcnr-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    ::chmod(dir_.c_str(), 0777);
    auto c = smc::documents::load_supervisor_config(src("edge/configs/smc2.textproto"));
    const double cutoff = wide_per_tick > 1 ? 3500 : 500;
    const uint32_t order = wide_per_tick > 1 ? 8 : 2;
    c.mutable_simulation()->set_f_y_wide_samples_per_tick(static_cast<uint32_t>(wide_per_tick));
    c.mutable_simulation()->set_f_y_wide_cutoff_hz(cutoff);
    c.mutable_simulation()->set_f_y_wide_order(order);
    c.mutable_operation()->set_wideband_samples_per_tick(static_cast<uint32_t>(wide_per_tick));
    c.mutable_operation()->set_wideband_cutoff_hz(cutoff);
    c.mutable_operation()->set_wideband_filter_order(order);
    auto* model = c.mutable_milling_model();
    model->mutable_workpiece()->set_width_mm(25);
    for (const double r :
         smc::machining::eccentric_runout_um(static_cast<int>(model->cutter().teeth()), 10)) {
      model->mutable_cutter()->add_radial_runout_um(r);
    }
    auto* pass = c.mutable_program()->mutable_passes(0);
    pass->set_depth_mm(5.5);
    pass->set_spindle_rpm(3000);
    pass->set_feedrate_mm_s(0.1 * c.operation().teeth() * 3000 / 60.0);
    c.mutable_program()->set_total_depth_mm(5.5);
    std::string text;
    ASSERT_TRUE(google::protobuf::TextFormat::PrintToString(c, &text));
    config_ = write("runout.textproto", text);
    int st = -1;
    const std::string out = capture(src("deploy/linuxcnc/run.sh") + " start --dir " +
                                        (dir_ / "cnc").string() + " --dyno " + config_,
                                    &st);
    ASSERT_EQ(st, 0) << out;
    started_ = true;
  }
  // 15 s of the run: the controller holds F_ref (95 N at this speed) with
  // a small feed, and the whole pass would take minutes; the run stops at
  // the time limit (status 3) with its summary written.
  cfg::RunSummary cut(const std::string& name) {
    int st = -1;
    const std::string out = simulate(config_, name, &st, 15);
    EXPECT_EQ(st, 3) << out;
    cfg::RunSummary s;
    smc::documents::load((dir_ / name / "summary.json").string(), s);
    return s;
  }
  std::string config_;
};

TEST_F(LinuxCncRunout, TheWidebandChannelKeepsRunoutFromReadingAsChatter) {
  // With the dynamometer's wideband F_y (smc-force-y-wide and its presence
  // bit, through the sampler): E judges its estimate, and the cut is stable.
  const cfg::RunSummary wide = cut("wide");
  const EstimateSeen wide_q = estimate_seen((dir_ / "wide" / "revolutions.csv").string());
  std::printf(
      "with the wideband channel: chatter events %u, E's estimate in %d revolutions, "
      "median q %.3f\n",
      wide.chatter_events(), wide_q.revolutions, wide_q.median_q);
  EXPECT_GT(wide_q.revolutions, 300);
  EXPECT_EQ(wide.chatter_events(), 0u) << "runout read as chatter";
  // A sensor without the channel: the presence bit undriven and false. E
  // judges S alone, and runout's share of F_z reads as chatter.
  int st = -1;
  std::string h = as_mill("halcmd unlinkp smc-dyno.wideband", &st);
  ASSERT_EQ(st, 0) << h;
  h = as_mill("halcmd sets smc-force-y-wide-present FALSE", &st);
  ASSERT_EQ(st, 0) << h;
  const cfg::RunSummary alone = cut("alone");
  const EstimateSeen alone_q = estimate_seen((dir_ / "alone" / "revolutions.csv").string());
  std::printf("without it: chatter events %u, first at %.2f s, E's estimate in %d revolutions\n",
              alone.chatter_events(), alone.chatter_detected_s(), alone_q.revolutions);
  EXPECT_EQ(alone_q.revolutions, 0);
  EXPECT_GE(alone.chatter_events(), 1u) << "S alone should read this runout as chatter";
}

// The same cut with the dynamometer's wideband channel sampled five times a
// servo period (10 kHz, through an eighth-order filter at 3.5 kHz, as the
// shipped configurations have it, and E's rules chosen for that rate): the
// sampler carries the period's five samples (smc-force-y-wide-sub-0..3,
// smc-force-y-wide and their count), E estimates the vibration at that
// rate on LinuxCNC too (a count other than the configuration's would hold
// the feed), and the cut is stable. The configuration's edge, told one
// sample a period, refuses the faster channel: E's error holds the feed.
class LinuxCncWideband : public LinuxCncRunout {
 protected:
  void SetUp() override { start(5); }
};

TEST_F(LinuxCncWideband, FiveSamplesAPeriodReachModuleE) {
  int st = -1;
  const std::string samples = as_mill("halcmd getp smc-dyno.wide-samples", &st);
  ASSERT_EQ(st, 0) << samples;
  EXPECT_EQ(std::atoi(samples.c_str()), 5) << samples;
  const cfg::RunSummary fast = cut("fast");
  const EstimateSeen q = estimate_seen((dir_ / "fast" / "revolutions.csv").string());
  std::printf(
      "the channel at 10 kHz on LinuxCNC: chatter events %u, faults %d, E's estimate in %d "
      "revolutions, median q %.3f\n",
      fast.chatter_events(), fast.faults_size(), q.revolutions, q.median_q);
  EXPECT_GT(q.revolutions, 250);  // of about 320 in the cut
  EXPECT_EQ(fast.chatter_events(), 0u) << "runout read as chatter";
  EXPECT_EQ(fast.faults_size(), 0) << smc::documents::to_json(fast);
  // An edge that expects one sample a period gets five: the drive reads the
  // dynamometer's count before anything moves and refuses the run, naming
  // both fields and the fix (before, E failed in the cut and held the feed
  // there).
  auto c = smc::documents::load_supervisor_config(config_);
  c.mutable_operation()->set_wideband_samples_per_tick(1);
  std::string text;
  ASSERT_TRUE(google::protobuf::TextFormat::PrintToString(c, &text));
  const std::string once = write("once.textproto", text);
  const double x_before = pin("joint.0.pos-fb");
  const std::string out = simulate(once, "once", &st, 15);
  EXPECT_DOUBLE_EQ(pin("joint.0.pos-fb"), x_before) << "the axis did not move";
  std::printf("told one sample a period: exit %d: %s\n", st, out.c_str());
  EXPECT_EQ(st, 2) << "refused before the run: " << out;
  EXPECT_NE(out.find("LinuxCNC's dynamometer gives module E's wideband channel 5 samples a "
                     "period (smc-force-y-wide-samples), but the configuration says 1 "
                     "(operation.wideband_samples_per_tick)"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("nothing was moved"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "once" / "summary.json")) << "no run";
}

// A machine that is not homed refuses the run before anything moves, naming
// what is missing.
TEST_F(LinuxCncDyno, AMachineNotHomedIsRefusedBeforeAnythingMoves) {
  python(
      "c.mode(linuxcnc.MODE_MANUAL); c.wait_complete(5); c.teleop_enable(0); "
      "c.wait_complete(5); c.unhome(0)");
  int st = -1;
  const std::string out = simulate(src("edge/configs/smc2.textproto"), "unhomed", &st);
  EXPECT_EQ(st, 2) << out;
  EXPECT_NE(out.find("not homed"), std::string::npos) << out;
}

// On the cell's side: a job sent to a LinuxCNC mill in E-stop fails at once
// with the reason, and the cell keeps it (failed, with its history) -- it is
// neither lost nor cut.
TEST_F(LinuxCncCell, AJobForAMillInEStopFailsWithTheReason) {
  int st = -1;
  const std::string e = capture(src("deploy/linuxcnc/run.sh") +
                                    " exec python3 -c 'import linuxcnc; c = linuxcnc.command(); "
                                    "c.state(linuxcnc.STATE_ESTOP); c.wait_complete(5)' 2>&1",
                                &st);
  ASSERT_EQ(st, 0) << e;
  const std::string id = submit(src("cell/jobs/transfer_line.textproto"));
  ASSERT_FALSE(id.empty());
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < until && !store::is_terminal(job(id).state)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  const std::string h = history(id);
  EXPECT_EQ(job(id).state, cfg::JOB_FAILED) << h;
  EXPECT_NE(h.find("LinuxCNC is in E-stop"), std::string::npos) << h;
  EXPECT_TRUE(read_watch(watch_file()).empty() ||
              full_passes(read_watch(watch_file()), "mill-1", -20, 170).empty())
      << "nothing was cut";
}

// The paper's job-shop run (SMC II) cut by LinuxCNC beside the same run on
// the simulated mill (smc-edge simulate with and without --drive linuxcnc).
// Tolerances, and why:
//  - passes, rewrites: equal;
//  - chatter detected after the first contact: within 0.3 s (7.5
//    revolutions at 1500 rpm) of the simulated mill's 2.56 s: the same
//    physics grows the same chatter, and E decides once per revolution,
//    but on LinuxCNC the feed reaches the part along its own acceleration
//    ramp and the edge's feed commands reach the motion with the host's
//    latency, so the chatter's onset after contact spreads over 2.48-2.71
//    s in 28 runs on an idle host (the simulated mill's 2.52 s), and E's
//    delay from it over 0.8-4.75 revolutions (the simulated mill's 0.99;
//    0.59-1.85 in ten runs with E's confirmed climb).
//    Detection after contact: 2.595-2.714 s on an idle host, 2.794 s in a
//    run under the whole suite's load. (The bound was 0.2 s while the
//    simulated mill detected at 2.60 s; E's steep rule caught it a
//    revolution earlier there and the suite's run went 0.234 s over.)
//  - the chatter label: the virtual dynamometer's vibration
//    (smc-vibration-y) reaches the trace in every sample in contact, so
//    the run's summary labels chatter's onset on LinuxCNC as the simulated
//    mill's does from its own. The onset and E's delay from it are printed,
//    not compared: on LinuxCNC the paper's chatter (750 Hz) can draw onto
//    the spindle's 30th order (751.5 Hz at LinuxCNC's 1503 rpm) as it
//    grows; the revolution-to-revolution change that the label reads then
//    falls back after two revolutions, and in some runs the label finds no
//    onset (deploy/linuxcnc/README.md, "Chatter's onset on LinuxCNC");
//  - overshoot: within 15 points of F_ref: the peak is reached while
//    chatter grows, and LinuxCNC's hold decelerates (20 ms at 10 mm/s);
//  - steady-state error of the passes that did not chatter: within 0.5
//    points;
//  - cycle time: longer by LinuxCNC's spindle start, approach and the
//    rewrite's stop, abort, retract and restart, at most 6 s + 4 s;
//  - the rewrite's hand-over: LinuxCNC's abort stops the spindle with the
//    tool in the cut, and the spindle ran down to 0 rpm before the
//    remainder lifted the tool (in one run the chatter then regrew to the
//    force sensor's limit); the drive restarts it and lifts the tool in
//    one MDI line first, so the spindle stays above 40 % of its speed
//    until the cutter moves away (951-1418 rpm at the lowest in twelve
//    runs, 0 before).
TEST_F(LinuxCncDyno, TheJobShopRunAgreesWithTheSimulatedMill) {
  int st = -1;
  const std::string out = simulate(src("edge/configs/smc2.textproto"), "lcnc", &st, 120);
  ASSERT_EQ(st, 0) << out;
  std::printf("%s", out.c_str());
  const std::string sim_dir = (dir_ / "sim").string();
  const std::string sim_out =
      capture(smc::test::bin_path("smc-edge") + " simulate --quiet --config " +
                  src("edge/configs/smc2.textproto") + " --out " + sim_dir + " 2>&1",
              &st);
  ASSERT_EQ(st, 0) << sim_out;
  cfg::RunSummary lc, sim;
  smc::documents::load((dir_ / "lcnc" / "summary.json").string(), lc);
  smc::documents::load(sim_dir + "/summary.json", sim);
  ASSERT_GT(lc.passes_size(), 0);
  ASSERT_GT(sim.passes_size(), 0);
  const double lc_detect = lc.chatter_detected_s() - lc.passes(0).contact_s();
  const double sim_detect = sim.chatter_detected_s() - sim.passes(0).contact_s();
  std::printf("LinuxCNC / simulated: chatter onset %.3f / %.3f s, detected %.3f / %.3f s\n",
              lc.chatter_onset_s(), sim.chatter_onset_s(), lc.chatter_detected_s(),
              sim.chatter_detected_s());
  std::printf(
      "LinuxCNC / simulated: passes %u / %u, rewrites %u / %u, chatter detected %.3f / "
      "%.3f s after contact, overshoot %.1f / %.1f %%, cycle %.1f / %.1f s\n",
      lc.passes_completed(), sim.passes_completed(), lc.program_rewrites(), sim.program_rewrites(),
      lc_detect, sim_detect, lc.overshoot_pct(), sim.overshoot_pct(), lc.cycle_time_s(),
      sim.cycle_time_s());
  EXPECT_TRUE(lc.completed());
  EXPECT_EQ(lc.passes_completed(), sim.passes_completed());
  EXPECT_EQ(lc.program_rewrites(), sim.program_rewrites());
  EXPECT_GT(sim_detect, 0);
  EXPECT_NEAR(lc_detect, sim_detect, 0.3);
  const auto seen = vibration_seen((dir_ / "lcnc" / "samples.csv").string());
  EXPECT_GT(seen.in_contact, 10000) << "LinuxCNC's run cut for 5 s and more";
  EXPECT_EQ(seen.known, seen.in_contact) << "samples in contact without the vibration";
  // (A vibration that crosses 0 reads 0 to 1 nm now and then.)
  EXPECT_GT(seen.nonzero, 0.99 * seen.in_contact) << "the dynamometer's vibration is undriven";
  // E's delay from the onset, in revolutions at the paper's 1500 rpm.
  auto delay = [](const cfg::RunSummary& s) {
    if (!(s.chatter_onset_s() > 0 && s.chatter_detected_s() > 0)) return std::string("- (none)");
    char text[32];
    std::snprintf(text, sizeof text, "%.2f",
                  (s.chatter_detected_s() - s.chatter_onset_s()) * 1500 / 60);
    return std::string(text);
  };
  std::printf("E's delay from the onset, revolutions: LinuxCNC %s, simulated %s\n",
              delay(lc).c_str(), delay(sim).c_str());
  EXPECT_NEAR(lc.overshoot_pct(), sim.overshoot_pct(), 15.0);
  for (int i = 0; i < lc.passes_size() && i < sim.passes_size(); ++i) {
    if (lc.passes(i).chatter() || sim.passes(i).chatter()) continue;
    EXPECT_NEAR(lc.passes(i).steady_state_error_pct(), sim.passes(i).steady_state_error_pct(), 0.5)
        << "pass " << i;
  }
  const double extra = lc.cycle_time_s() - sim.cycle_time_s();
  EXPECT_GE(extra, 0.0);
  EXPECT_LE(extra, 10.0);
  ASSERT_GT(lc.program_rewrites(), 0u);
  const double slowest = slowest_spindle_until_moved((dir_ / "lcnc" / "samples.csv").string(),
                                                     lc.chatter_detected_s());
  std::printf("the spindle during the rewrite's hand-over: %.0f rpm at the lowest\n", slowest);
  EXPECT_GT(slowest, 0.4 * 1500) << "the spindle ran down with the tool in the cut";
  // The exit: the teeth cut until their tips pass the part's end, on the
  // dynamometer as on the simulated mill (it used to read the part's last
  // bin as cut once the leading edge reached it, and every cut ended the
  // cutter's radius early, at X125 of 150). Within a revolution at the
  // machine's highest feed (36 mm/s at 1500 rpm: 1.44 mm) twice over: the
  // controller raises the feed as the force falls, and LinuxCNC's run
  // differs from run to run (X141.0 and X142.1 against X140.9 in two runs).
  // Module E reads the vibration from the dynamometer's wideband F_y on
  // LinuxCNC too (smc-edge.hal, sampler pins 10-11): its q is above 0 (with
  // the channel's noise taken out, a revolution that only repeats reads 0)
  // in at least half as many of the cut's revolutions as on the simulated
  // mill, and it reads the same steady cut alike (the median q, within a third:
  // LinuxCNC's feed ramps and holds differ).
  const EstimateSeen lc_q = estimate_seen((dir_ / "lcnc" / "revolutions.csv").string());
  const EstimateSeen sim_q = estimate_seen(sim_dir + "/revolutions.csv");
  std::printf("E's estimate judged in %d / %d revolutions in contact, median q %.3f / %.3f\n",
              lc_q.revolutions, sim_q.revolutions, lc_q.median_q, sim_q.median_q);
  ASSERT_GT(sim_q.revolutions, 50);
  EXPECT_GT(lc_q.revolutions, sim_q.revolutions / 2);
  EXPECT_NEAR(lc_q.median_q, sim_q.median_q, sim_q.median_q / 3);
  const double lc_end = last_cutting_x((dir_ / "lcnc" / "revolutions.csv").string(), 50);
  const double sim_end = last_cutting_x(sim_dir + "/revolutions.csv", 50);
  std::printf("last revolution with F_Y above 50 N: X%.2f / X%.2f\n", lc_end, sim_end);
  EXPECT_GT(sim_end, 130.0);
  EXPECT_NEAR(lc_end, sim_end, 2 * 36.0 * 60.0 / 1500);
}
