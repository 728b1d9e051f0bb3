// A job's history as the dashboard serves it (GET /api/jobs/ID/history and
// history.csv), from a cell database written through the store as the cell
// service writes it: a 60 s job of 1500 revolutions with a rewrite.

#include "job_history.hpp"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"

namespace store = smc::cell::store;

namespace {

struct Db {
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("smc-history-" + std::to_string(::getpid()));
  std::string path;
  std::string job_id;
  Db() {
    std::filesystem::create_directories(dir);
    path = (dir / "cell.db").string();
    auto db = store::Store::open(path, store::OpenMode::kCreate);
    store::seed_demo(db);
    smc::config::Job spec;
    spec.set_part_id("housing-js");
    job_id = db.submit_job(spec).id;
    // 60 s at 1500 rpm: 1500 revolutions, the second half after a rewrite.
    std::vector<store::JobRevolution> revs;
    for (int i = 0; i < 1500; ++i) {
      store::JobRevolution r;
      r.attempt = 1;
      r.t_s = 0.04 * i;
      r.revolution = static_cast<std::uint32_t>(i);
      r.pass_index = i < 750 ? 0 : 1;
      r.pass_count = i < 750 ? 1 : 2;
      r.depth_mm = i < 750 ? 2 : 1;
      r.f_y_n = 180 + 5 * std::sin(i);
      r.f_ref_n = 180;
      r.feedrate_mm_s = 6.5;
      r.feed_per_tooth_mm = 0.065;
      r.spindle_rpm = 1500;
      r.spindle_power_w = i == 10 ? std::nan("") : 700;
      r.in_contact = true;
      r.chatter = i >= 740 && i < 745;
      revs.push_back(r);
    }
    db.append_revolutions(job_id, revs);
    db.add_program(job_id, {1, 1, 0, "(rewrite 1)\nG0 Z-1\n", 2});
    db.add_program(job_id, {1, 1, 0, "(the same revision again: kept once)\n", 2});
    db.note_event(job_id, "chatter event 7: detected at 750 Hz in pass 1; program now 2 passes");
  }
  ~Db() { std::filesystem::remove_all(dir); }
};

google::protobuf::Value parse(const std::string& text) {
  google::protobuf::Value v;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(text, &v).ok()) << text.substr(0, 200);
  return v;
}

const google::protobuf::Value& at(const google::protobuf::Value& v, const std::string& k) {
  return v.struct_value().fields().at(k);
}

}  // namespace

TEST(JobHistory, TheRecordedRevolutionsEventsAndProgramsOfAJob) {
  Db db;
  smc::dashboard::JobHistory h(db.path);
  const auto json = h.json(db.job_id);
  ASSERT_TRUE(json.has_value());
  const auto v = parse(*json);
  EXPECT_EQ(at(v, "job_id").string_value(), db.job_id);
  EXPECT_EQ(at(v, "part_id").string_value(), "housing-js");
  const auto& revs = at(v, "revolutions");
  EXPECT_EQ(at(revs, "count").number_value(), 1500);
  EXPECT_EQ(at(revs, "t").list_value().values_size(), 1500);
  EXPECT_DOUBLE_EQ(at(revs, "t").list_value().values(1499).number_value(), 0.04 * 1499);
  EXPECT_EQ(at(revs, "pass_index").list_value().values(1499).number_value(), 1);
  EXPECT_TRUE(at(revs, "spindle_power_w").list_value().values(10).has_null_value())
      << "a drive without power: null, not a number";
  EXPECT_TRUE(at(revs, "chatter").list_value().values(742).bool_value());
  ASSERT_EQ(at(v, "programs").list_value().values_size(), 1);
  EXPECT_EQ(at(at(v, "programs").list_value().values(0), "gcode").string_value(),
            "(rewrite 1)\nG0 Z-1\n");
  bool note = false;
  for (const auto& e : at(v, "events").list_value().values()) {
    note = note || at(e, "reason").string_value().find("chatter event 7") == 0;
  }
  EXPECT_TRUE(note);
  EXPECT_FALSE(h.json("job-999999").has_value());
}

TEST(JobHistory, CsvHasOneRowPerRevolution) {
  Db db;
  smc::dashboard::JobHistory h(db.path);
  const auto csv = h.csv(db.job_id);
  ASSERT_TRUE(csv.has_value());
  std::size_t lines = 0;
  for (char c : *csv) lines += c == '\n' ? 1 : 0;
  EXPECT_EQ(lines, 1501u);
  EXPECT_EQ(csv->rfind("job_id,attempt,t_s,revolution,pass,pass_count,depth_mm,f_y_peak_n,", 0),
            0u);
  // Revolution 10 (no power) leaves the power field empty; passes are 1-based.
  const std::string row10 = db.job_id + ",1,0.400000,10,1,1,2.0000,";
  EXPECT_NE(csv->find(row10), std::string::npos);
  EXPECT_NE(csv->find(",1500.00,,1,0\n"), std::string::npos);
  EXPECT_FALSE(h.csv("job-999999").has_value());
}

TEST(JobHistory, AMissingDatabaseIsRefusedNamingTheFix) {
  smc::dashboard::JobHistory h("/nonexistent/cell.db");
  try {
    (void)h.json("job-000001");
    ADD_FAILURE() << "read a missing database";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("smc-cell db init"), std::string::npos) << e.what();
  }
}
