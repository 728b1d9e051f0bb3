// Catalog documents: apply (checked as a whole, idempotent, recorded),
// export and the round trip, bad documents refused naming file, field and
// fix with nothing written, retirement.

#include <gmock/gmock.h>

#include <filesystem>
#include <fstream>

#include "smc/cell/store/catalog_docs.hpp"
#include "smc/cell/store/job_file.hpp"
#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::HasSubstr;

class CellCatalog : public StoreTest {
 protected:
  std::string doc(const std::string& name, const std::string& text) {
    const auto p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  // Applies `text` (one document) to a seeded database and returns the
  // error; the database must be as before.
  std::string refused(const std::string& text) {
    Store s = seeded();
    const Counts before = s.counts();
    const auto hist = s.history().size();
    const std::string file = doc("bad.textproto", text);
    try {
      apply_catalog(s, load_catalog({file}), {});
      ADD_FAILURE() << "applied: " << text;
      return {};
    } catch (const CatalogError& e) {
      const Counts after = s.counts();
      EXPECT_EQ(after.machines, before.machines);
      EXPECT_EQ(after.parts, before.parts);
      EXPECT_EQ(after.models, before.models);
      EXPECT_EQ(s.history().size(), hist) << "nothing written";
      return e.what();
    }
  }
};

std::string read_all(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST_F(CellCatalog, TheShippedCatalogRoundTripsThroughExport) {
  Store a = Store::open((dir_ / "a.db").string());
  const auto created = apply_catalog(a, load_catalog({default_catalog_dir()}), {});
  EXPECT_EQ(created.size(), 11u);
  write_catalog(export_catalog(a), (dir_ / "export-a").string());
  Store b = Store::open((dir_ / "b.db").string());
  apply_catalog(b, load_catalog({(dir_ / "export-a").string()}), {.author = "t"});
  write_catalog(export_catalog(b), (dir_ / "export-b").string());
  for (const char* f : {"machines.textproto", "tools.textproto", "materials.textproto",
                        "parts.textproto", "models.textproto"}) {
    const auto x = read_all(dir_ / "export-a" / f);
    EXPECT_FALSE(x.empty()) << f;
    EXPECT_EQ(x, read_all(dir_ / "export-b" / f)) << f;
  }
}

TEST_F(CellCatalog, ApplyIsIdempotentShowsItsChangesAndRecordsThem) {
  Store s = seeded();
  const std::string file = doc("m.textproto",
                               "machines { id: \"mill-1\" name: \"face mill mill-1 (the paper's "
                               "machine)\" max_spindle_power_w: 900 max_feedrate_mm_s: 36 "
                               "max_spindle_rpm: 3000 }\n"
                               "machines { id: \"mill-3\" max_spindle_power_w: 2000 "
                               "max_feedrate_mm_s: 50 min_spindle_rpm: 200 max_spindle_rpm: 6000 "
                               "drive: \"linuxcnc\" }\n");
  const auto dry = apply_catalog(s, load_catalog({file}), {.dry_run = true});
  ASSERT_EQ(dry.size(), 2u);
  EXPECT_EQ(dry[0].action, "updated");
  EXPECT_THAT(dry[0].detail, HasSubstr("max_spindle_power_w"));
  EXPECT_EQ(dry[1].action, "created");
  EXPECT_DOUBLE_EQ(s.machine("mill-1")->max_spindle_power_w, 745.7) << "a dry run writes nothing";
  EXPECT_FALSE(s.machine("mill-3"));
  apply_catalog(s, load_catalog({file}), {.author = "ana", .reason = "new spindle"});
  EXPECT_DOUBLE_EQ(s.machine("mill-1")->max_spindle_power_w, 900);
  const auto m3 = s.machine("mill-3");
  ASSERT_TRUE(m3);
  EXPECT_EQ(m3->drive, "linuxcnc");
  EXPECT_DOUBLE_EQ(m3->min_spindle_rpm, 200);
  EXPECT_EQ(m3->name, "mill-3");
  const auto h = s.history("machine", "mill-1");
  ASSERT_FALSE(h.empty());
  EXPECT_EQ(h.back().action, "updated");
  EXPECT_EQ(h.back().author, "ana");
  EXPECT_EQ(h.back().reason, "new spindle");
  EXPECT_THAT(h.back().detail, HasSubstr("max_spindle_power_w"));
  const auto again = apply_catalog(s, load_catalog({file}), {});
  for (const auto& c : again) EXPECT_EQ(c.action, "unchanged") << c.kind << " " << c.id;
  EXPECT_EQ(s.history("machine", "mill-1").size(), h.size());
}

// A machine's wideband channel (module E's): kept, exported, updated, and
// each field checked against what the edge and the machine's drive take.
TEST_F(CellCatalog, AMachinesWidebandChannelIsKeptExportedAndChecked) {
  Store s = seeded();
  const std::string machine =
      "machines { id: \"mill-3\" max_spindle_power_w: 745.7 max_feedrate_mm_s: 36 "
      "max_spindle_rpm: 3000 ";
  const std::string file =
      doc("m.textproto", machine + "wideband { samples_per_tick: 1 cutoff_hz: 500 } }\n");
  apply_catalog(s, load_catalog({file}), {});
  const auto m3 = s.machine("mill-3");
  ASSERT_TRUE(m3);
  EXPECT_EQ(m3->wideband.samples_per_tick, 1u);
  EXPECT_DOUBLE_EQ(m3->wideband.cutoff_hz, 500);
  EXPECT_EQ(m3->wideband.filter_order, 2u) << "the edge's default order, written down";
  EXPECT_DOUBLE_EQ(m3->wideband.noise_rms_n, 0);
  EXPECT_TRUE(s.machine("mill-1")->wideband.is_default()) << "the demo's mills: the default";
  for (const auto& c : apply_catalog(s, load_catalog({file}), {})) {
    EXPECT_EQ(c.action, "unchanged") << c.kind << " " << c.id << ": " << c.detail;
  }
  const auto exported = export_catalog(s);
  int with_channel = 0;
  for (const auto& m : exported.machines()) {
    if (!m.has_wideband()) continue;
    ++with_channel;
    EXPECT_EQ(m.id(), "mill-3");
    EXPECT_EQ(m.wideband().filter_order(), 2u);
  }
  EXPECT_EQ(with_channel, 1) << "a default channel is not written out";
  const std::string faster =
      doc("m2.textproto", machine +
                              "wideband { samples_per_tick: 5 cutoff_hz: 3500 filter_order: 8 "
                              "noise_rms_n: 2 } }\n");
  const auto changed = apply_catalog(s, load_catalog({faster}), {});
  ASSERT_EQ(changed.size(), 1u);
  EXPECT_EQ(changed[0].action, "updated");
  EXPECT_THAT(changed[0].detail, HasSubstr("wideband.samples_per_tick"));
  EXPECT_EQ(s.machine("mill-3")->wideband.samples_per_tick, 5u);

  const auto bad = [&](const std::string& channel, const std::string& drive = "simulated") {
    return refused(machine + "drive: \"" + drive + "\" wideband { " + channel + " } }\n");
  };
  EXPECT_THAT(bad("cutoff_hz: 500"), HasSubstr("'mill-3'.wideband.samples_per_tick: is 0 but"));
  EXPECT_THAT(bad("samples_per_tick: 6 cutoff_hz: 500"),
              HasSubstr("wideband.samples_per_tick: must be 1-5, got 6"));
  EXPECT_THAT(bad("samples_per_tick: 3 cutoff_hz: 500"),
              HasSubstr("does not divide the simulated mill's 50 steps"));
  EXPECT_THAT(bad("samples_per_tick: 1 cutoff_hz: 1000"),
              HasSubstr("wideband.cutoff_hz: must be > 0 and below the channel's Nyquist "
                        "frequency (1000 Hz), got 1000"));
  EXPECT_THAT(bad("samples_per_tick: 1 cutoff_hz: 500 filter_order: 3"),
              HasSubstr("wideband.filter_order: must be even, 2-8, got 3"));
  EXPECT_THAT(bad("samples_per_tick: 1 cutoff_hz: 500 noise_rms_n: -1"),
              HasSubstr("wideband.noise_rms_n: must be 0-1000 N rms, got -1"));
  EXPECT_THAT(bad("samples_per_tick: 1 cutoff_hz: nan"), HasSubstr("fix:"));
  // A LinuxCNC drive takes any count its dynamometer brings, up to 5.
  apply_catalog(s,
                load_catalog({doc("m3.textproto",
                                  machine + "drive: \"linuxcnc\" wideband { samples_per_tick: 3 "
                                            "cutoff_hz: 2000 filter_order: 4 } }\n")}),
                {});
  EXPECT_EQ(s.machine("mill-3")->wideband.samples_per_tick, 3u);
}

// One document per kind with each class of error.
TEST_F(CellCatalog, BadDocumentsAreRefusedNamingFileFieldAndFix) {
  // Wrong type (a parse error: file:line:col).
  EXPECT_THAT(refused("machines { id: \"m\" max_spindle_power_w: \"lots\" }\n"),
              HasSubstr("bad.textproto:1:"));
  // Missing field.
  EXPECT_THAT(refused("tools { name: \"no id\" teeth: 4 radius_mm: 10 }\n"),
              HasSubstr("bad.textproto: tools[0] ''.id: missing"));
  // Out-of-range limits.
  const auto limits = refused(
      "machines { id: \"m9\" max_spindle_power_w: -5 max_feedrate_mm_s: 30 max_spindle_rpm: 100 "
      "min_spindle_rpm: 200 }\n");
  EXPECT_THAT(limits, HasSubstr("machines[0] 'm9'.max_spindle_power_w: must be > 0, got -5"));
  EXPECT_THAT(limits, HasSubstr("min_spindle_rpm: must be >= 0 and below max_spindle_rpm"));
  EXPECT_THAT(limits, HasSubstr("fix:"));
  EXPECT_THAT(refused("tools { id: \"t\" teeth: 0 radius_mm: 10 lead_angle_deg: 95 }\n"),
              HasSubstr("tools[0] 't'.lead_angle_deg: must be in [0, 90)"));
  // Unknown reference.
  const auto part = refused(
      "parts { id: \"p\" material_id: \"unobtainium\" tool_id: \"fm-r25-4t\" width_mm: 10 "
      "length_mm: 10 total_depth_mm: 1 feedrate_mm_s: 5 spindle_rpm: 1000 }\n");
  EXPECT_THAT(part, HasSubstr("parts[0] 'p'.material_id: unknown material 'unobtainium'"));
  EXPECT_THAT(part, HasSubstr("use one of: 6061-T6"));
  EXPECT_THAT(refused("models { id: \"x\" machine_id: \"mill-9\" tool_id: \"fm-r25-4t\" "
                      "material_id: \"6061-T6\" force_process { k_kn: 1 beta: 0.6 alpha: 0.6 } "
                      "}\n"),
              HasSubstr("models[0] 'x'.machine_id: unknown machine 'mill-9'"));
  EXPECT_THAT(refused("materials { id: \"steel\" }\nmaterials { id: \"steel\" }\n"),
              HasSubstr("the id is given twice"));
  // Duplicate id of an existing model with another document.
  EXPECT_THAT(refused("models { id: \"bracket-tl.mill-1.force\" machine_id: \"mill-1\" tool_id: "
                      "\"fm-r25-4t\" material_id: \"6061-T6\" part_id: \"bracket-tl\" "
                      "force_process { k_kn: 2 beta: 0.65 alpha: 0.63 } validated: true }\n"),
              HasSubstr("models are never replaced"));
  // A model with no document, and a bad milling model.
  EXPECT_THAT(refused("models { id: \"y\" machine_id: \"mill-1\" tool_id: \"fm-r25-4t\" "
                      "material_id: \"6061-T6\" }\n"),
              HasSubstr("has no model document"));
}

// Every kind against every class of error that applies to it: wrong type,
// missing field, unknown reference, out-of-range limit, duplicate id. Each
// is refused naming the file and the field, with a fix, and nothing is
// written (refused() checks the counts and the history).
TEST_F(CellCatalog, EachKindRefusesEachClassOfError) {
  struct Case {
    const char* what;
    std::string text;
    std::string expect;  // in the message
  };
  const std::string tool_ok = "id: \"t9\" teeth: 4 radius_mm: 10";
  const std::string part_ok =
      "material_id: \"6061-T6\" tool_id: \"fm-r25-4t\" width_mm: 10 length_mm: 50 "
      "total_depth_mm: 1 feedrate_mm_s: 5 spindle_rpm: 1000";
  const std::string model_refs =
      "machine_id: \"mill-1\" tool_id: \"fm-r25-4t\" material_id: \"6061-T6\"";
  const std::string force = "force_process { k_kn: 0.7 beta: 0.6 alpha: 0.6 }";
  const std::vector<Case> cases{
      // machines
      {"machine wrong type", "machines { id: 7 }", "bad.textproto:1:"},
      {"machine missing id",
       "machines { max_spindle_power_w: 1 max_feedrate_mm_s: 1 max_spindle_rpm: 1 }",
       "machines[0] ''.id: missing"},
      {"machine out of range",
       "machines { id: \"m9\" max_spindle_power_w: 1 max_feedrate_mm_s: 0 max_spindle_rpm: 1 }",
       "machines[0] 'm9'.max_feedrate_mm_s: must be > 0"},
      {"machine unknown drive",
       "machines { id: \"m9\" max_spindle_power_w: 1 max_feedrate_mm_s: 1 max_spindle_rpm: 1 "
       "drive: \"plc\" }",
       "machines[0] 'm9'.drive: unknown drive 'plc'"},
      {"machine duplicate",
       "machines { id: \"m9\" max_spindle_power_w: 1 max_feedrate_mm_s: 1 max_spindle_rpm: 1 }"
       "machines { id: \"m9\" max_spindle_power_w: 1 max_feedrate_mm_s: 1 max_spindle_rpm: 1 }",
       "machines[1] 'm9': the id is given twice"},
      // tools
      {"tool wrong type", "tools { id: \"t9\" teeth: -4 }", "bad.textproto:1:"},
      {"tool missing id", "tools { teeth: 4 radius_mm: 10 }", "tools[0] ''.id: missing"},
      {"tool out of range", "tools { id: \"t9\" teeth: 4 radius_mm: -1 }",
       "tools[0] 't9'.radius_mm: must be > 0"},
      {"tool duplicate", "tools { " + tool_ok + " } tools { " + tool_ok + " }",
       "tools[1] 't9': the id is given twice"},
      // materials
      {"material wrong type", "materials { id: [1] }", "bad.textproto:1:"},
      {"material missing id", "materials { name: \"steel\" }", "materials[0] ''.id: missing"},
      {"material duplicate", "materials { id: \"s\" } materials { id: \"s\" }",
       "materials[1] 's': the id is given twice"},
      // parts
      {"part wrong type", "parts { id: \"p9\" width_mm: \"wide\" }", "bad.textproto:1:"},
      {"part missing field",
       "parts { id: \"p9\" tool_id: \"fm-r25-4t\" width_mm: 10 length_mm: 50 "
       "total_depth_mm: 1 feedrate_mm_s: 5 spindle_rpm: 1000 }",
       "parts[0] 'p9'.material_id: missing"},
      {"part unknown reference",
       "parts { id: \"p9\" material_id: \"6061-T6\" tool_id: \"no-tool\" width_mm: 10 "
       "length_mm: 50 total_depth_mm: 1 feedrate_mm_s: 5 spindle_rpm: 1000 }",
       "parts[0] 'p9'.tool_id: unknown tool 'no-tool'"},
      {"part out of range",
       "parts { id: \"p9\" material_id: \"6061-T6\" width_mm: 10 length_mm: 50 "
       "total_depth_mm: 1 feedrate_mm_s: 5 spindle_rpm: 0 }",
       "parts[0] 'p9'.spindle_rpm: must be > 0"},
      {"part duplicate",
       "parts { id: \"p9\" " + part_ok + " } parts { id: \"p9\" " + part_ok + " }",
       "parts[1] 'p9': the id is given twice"},
      // models
      {"model wrong type", "models { id: \"x9\" validated: \"yes\" }", "bad.textproto:1:"},
      {"model missing field",
       "models { id: \"x9\" tool_id: \"fm-r25-4t\" material_id: \"6061-T6\" " + force + " }",
       "models[0] 'x9'.machine_id: missing"},
      {"model unknown reference",
       "models { id: \"x9\" " + model_refs + " part_id: \"no-part\" " + force + " }",
       "models[0] 'x9'.part_id: unknown part 'no-part'"},
      {"model out of range",
       "models { id: \"x9\" " + model_refs + " force_process { k_kn: -1 beta: 0.6 alpha: 0.6 } }",
       "models[0] 'x9'.force_process: k_kn, alpha and beta must be > 0"},
      {"model validity out of range",
       "models { id: \"x9\" " + model_refs + " " + force + " validity { max_depth_mm: -2 } }",
       "models[0] 'x9'.validity: bounds must be >= 0"},
      {"model duplicate",
       "models { id: \"x9\" " + model_refs + " " + force + " } models { id: \"x9\" " + model_refs +
           " " + force + " }",
       "models[1] 'x9': the id is given twice"},
  };
  for (const auto& c : cases) {
    const std::string msg = refused(c.text + "\n");
    EXPECT_THAT(msg, HasSubstr(c.expect)) << c.what;
    EXPECT_THAT(msg, HasSubstr("bad.textproto")) << c.what << ": the file is named";
    if (c.expect.find(".textproto:1:") == std::string::npos) {
      EXPECT_THAT(msg, HasSubstr("fix:")) << c.what << ": a fix is given";
    }
  }
}

TEST_F(CellCatalog, RetiredEntitiesStayButNewJobsRefuseThem) {
  Store s = seeded();
  s.retire("part", "housing-js", "ana", "superseded by housing-js2");
  EXPECT_TRUE(s.part("housing-js"));
  EXPECT_NE(s.part("housing-js")->retired_at_ms, 0);
  smc::config::Job j;
  j.set_part_id("housing-js");
  try {
    (void)s.submit_job(j);
    FAIL() << "a retired part was accepted";
  } catch (const JobRejected& e) {
    EXPECT_THAT(e.what(), HasSubstr("part 'housing-js' is retired"));
    EXPECT_THAT(e.what(), HasSubstr("use one of: bracket-tl"));
  }
  s.retire("machine", "mill-2", "ana", "sold");
  smc::config::Job pinned;
  pinned.set_part_id("bracket-tl");
  pinned.set_machine_id("mill-2");
  EXPECT_THROW((void)s.submit_job(pinned), JobRejected);
  EXPECT_THROW(s.retire("machine", "mill-2", "ana", "again"), StoreError);
  EXPECT_THROW(s.retire("machine", "mill-9", "ana", "x"), StoreError);
  EXPECT_THROW(s.retire("machine", "mill-1", "ana", ""), StoreError);
  // Retired models are not found for planning; the export leaves retired
  // entities out; a retired id is never reused.
  s.retire("model", "bracket-tl.mill-1.force", "ana", "re-identified");
  for (const auto& m : s.find_models("mill-1", "", "", "bracket-tl")) {
    EXPECT_NE(m.id, "bracket-tl.mill-1.force");
  }
  const auto exported = export_catalog(s);
  for (const auto& m : exported.machines()) EXPECT_NE(m.id(), "mill-2");
  const std::string file = doc("again.textproto",
                               "machines { id: \"mill-2\" max_spindle_power_w: 745.7 "
                               "max_feedrate_mm_s: 36 max_spindle_rpm: 3000 }\n");
  try {
    apply_catalog(s, load_catalog({file}), {});
    FAIL();
  } catch (const CatalogError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'mill-2' is retired; ids are never reused"));
  }
  const auto h = s.history("part", "housing-js");
  ASSERT_FALSE(h.empty());
  EXPECT_EQ(h.back().action, "retired");
  EXPECT_EQ(h.back().reason, "superseded by housing-js2");
}

// Changing a machine's limits sends the jobs planned for it back to be
// planned again; jobs planned for another machine stay planned.
TEST_F(CellCatalog, ChangingAMachinesLimitsReplansItsPlannedJobs) {
  Store s = seeded();
  const auto plan_for = [&](const std::string& machine) {
    smc::config::Job j;
    j.set_part_id("bracket-tl");
    const auto job = s.submit_job(j);
    s.set_plan(job.id, smc::config::SMC_I, "why", {}, machine);
    EXPECT_TRUE(s.transition(job.id, smc::config::JOB_QUEUED, smc::config::JOB_PLANNED, "p"));
    return job.id;
  };
  const auto on1 = plan_for("mill-1");
  const auto on2 = plan_for("mill-2");
  const std::string file = doc("m.textproto",
                               "machines { id: \"mill-1\" name: \"face mill mill-1 (the paper's "
                               "machine)\" max_spindle_power_w: 600 max_feedrate_mm_s: 36 "
                               "max_spindle_rpm: 3000 }\n");
  apply_catalog(s, load_catalog({file}), {.author = "ana", .reason = "spindle derated"});
  EXPECT_EQ(s.job(on1)->state, smc::config::JOB_QUEUED);
  EXPECT_THAT(s.events(on1).back().reason, HasSubstr("re-planned: machine mill-1 changed"));
  EXPECT_EQ(s.job(on2)->state, smc::config::JOB_PLANNED);
}

// Retiring a machine sends the jobs planned for it back to be planned again.
TEST_F(CellCatalog, RetiringAMachineReplansItsPlannedJobs) {
  Store s = seeded();
  smc::config::Job j;
  j.set_part_id("bracket-tl");
  const auto job = s.submit_job(j);
  s.set_plan(job.id, smc::config::SMC_I, "why", {}, "mill-2");
  ASSERT_TRUE(s.transition(job.id, smc::config::JOB_QUEUED, smc::config::JOB_PLANNED, "p"));
  s.retire("machine", "mill-2", "ana", "sold");
  EXPECT_EQ(s.job(job.id)->state, smc::config::JOB_QUEUED);
  EXPECT_THAT(s.events(job.id).back().reason, HasSubstr("machine mill-2 retired (sold)"));
}

}  // namespace
}  // namespace smc::cell::store::test
