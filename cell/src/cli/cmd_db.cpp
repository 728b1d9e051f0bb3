// smc-cell db init|show: create, migrate, seed and inspect the cell database
// (smc_cell_store, cell/store/README.md). Exit codes: 0 ok, 1 the database
// cannot be used (errors name the file and the SQL), 2 a bad model document.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "registry.hpp"
#include "smc/cell/store/catalog_docs.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"

namespace {

using smc::cell::cli::add_db_option;
using smc::cell::cli::Failure;
namespace store = smc::cell::store;

void print_summary(store::Store& s) {
  const store::Counts c = s.counts();
  std::printf("%s\n", s.path().c_str());
  std::printf("  schema version %d (this smc-cell: %d), WAL mode\n", s.schema_version(),
              store::Store::latest_schema_version());
  std::printf("  machines %lld, tools %lld, materials %lld, parts %lld, process models %lld\n",
              static_cast<long long>(c.machines), static_cast<long long>(c.tools),
              static_cast<long long>(c.materials), static_cast<long long>(c.parts),
              static_cast<long long>(c.models));
  std::string by_state;
  for (const auto& [state, n] : c.jobs_by_state) {
    by_state += (by_state.empty() ? "" : ", ") + std::string(store::state_name(state)) + " " +
                std::to_string(n);
  }
  std::printf("  jobs %lld%s%s%s, job events %lld\n", static_cast<long long>(c.jobs),
              by_state.empty() ? "" : " (", by_state.c_str(), by_state.empty() ? "" : ")",
              static_cast<long long>(c.job_events));
}

void print_catalog(store::Store& s) {
  for (const auto& m : s.machines()) {
    std::printf("  machine  %-12s %g W, %g mm/s, %g rpm  %s\n", m.id.c_str(), m.max_spindle_power_w,
                m.max_feedrate_mm_s, m.max_spindle_rpm, m.name.c_str());
  }
  for (const auto& t : s.tools()) {
    std::printf("  tool     %-12s %u teeth, R %g mm, lead %g deg  %s\n", t.id.c_str(), t.teeth,
                t.radius_mm, t.lead_angle_deg, t.name.c_str());
  }
  for (const auto& m : s.materials()) {
    std::printf("  material %-12s %s\n", m.id.c_str(), m.name.c_str());
  }
  for (const auto& p : s.parts()) {
    int validated = 0, candidates = 0;
    for (const auto& m : s.find_models("", "", p.material_id, p.id)) {
      (m.validated ? validated : candidates) += 1;
    }
    std::printf(
        "  part     %-12s %s, %g x %g mm, %g mm deep at %g mm/s, %g rpm; models: %d "
        "validated, %d candidate  %s\n",
        p.id.c_str(), p.material_id.c_str(), p.width_mm, p.length_mm, p.total_depth_mm,
        p.feedrate_mm_s, p.spindle_rpm, validated, candidates, p.name.c_str());
  }
}

}  // namespace

SMC_CELL_COMMAND(db, 21) {
  auto* db = app.add_subcommand("db", "The cell database: create, migrate, seed, inspect");
  db->require_subcommand(1);

  struct InitArgs {
    std::string db;
    bool seed = false;
    std::string catalog = store::default_catalog_dir();
  };
  auto init_args = std::make_shared<InitArgs>();
  auto* init = db->add_subcommand(
      "init",
      "Create the database (or bring an existing one to the latest schema); with --seed add "
      "the demo's machines, tool, material and parts (idempotent)");
  add_db_option(init, init_args->db);
  init->add_flag(
      "--seed", init_args->seed,
      "Add the demo seed data: the catalog documents of cell/catalog (the paper's "
      "machine as mill-1 and mill-2, its face mill, 6061-T6, bracket-tl with "
      "validated models, housing-js and cover-jsp without), applied as `smc-cell catalog "
      "apply` does");
  init->add_option("--catalog", init_args->catalog, "Catalog folder for --seed")
      ->capture_default_str();
  init->callback([init_args] {
    store::Store s = store::Store::open(init_args->db, store::OpenMode::kCreate);
    if (init_args->seed) {
      try {
        const auto inserted = store::seed_demo(s, store::SeedOptions{init_args->catalog});
        std::printf("seed: %lld entities added from %s%s\n", static_cast<long long>(inserted),
                    init_args->catalog.c_str(), inserted == 0 ? " (already seeded)" : "");
      } catch (const store::CatalogError& e) {
        throw Failure(2, std::string(e.what()) + "\nseed: nothing written");
      }
    }
    print_summary(s);
  });

  auto show_db = std::make_shared<std::string>();
  auto* show = db->add_subcommand("show", "Schema version, counts and the catalog");
  add_db_option(show, *show_db);
  show->callback([show_db] {
    store::Store s = store::Store::open(*show_db, store::OpenMode::kExisting);
    print_summary(s);
    print_catalog(s);
  });
}
