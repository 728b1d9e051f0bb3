// smc-cell part show ID: one part as a cell engineer wants to see it — its
// programmed cut, the models the cell holds for it on each machine (their
// provenance, validation, suspicion and fit), what a job of it would get
// now and why, its jobs and its history.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "registry.hpp"
#include "smc/cell/candidates.hpp"
#include "smc/cell/store/store.hpp"

namespace {

using smc::cell::cli::add_db_option;
using smc::cell::cli::Failure;
namespace store = smc::cell::store;
namespace cfg = smc::config;

void print_model(const store::ProcessModel& m) {
  std::printf("    %-28s %-13s %-10s %s%s\n", m.id.c_str(),
              std::string(store::kind_name(m.kind)).c_str(),
              std::string(store::provenance_name(m.provenance)).c_str(),
              m.validated ? "validated" : "not validated",
              m.part_id.empty() ? ", any part of the material" : "");
  if (m.kind == store::ModelKind::kForceProcess) {
    std::printf("      F_Y = %.3f kN d^%.3f f^%.3f\n", m.force.k_kn(), m.force.beta(),
                m.force.alpha());
  }
  if (m.fit.samples() > 0) {
    std::printf("      fitted from %u revolutions: R^2 %.3f, rms residual %.1f N\n",
                m.fit.samples(), m.fit.r_squared(), m.fit.rms_residual_n());
  }
  const auto& v = m.validity;
  if (v.ByteSizeLong() > 0) {
    std::printf("      valid: %g-%g rpm, to %g mm deep, %g-%g mm wide (0: no bound)\n",
                v.min_spindle_rpm(), v.max_spindle_rpm(), v.max_depth_mm(), v.min_width_mm(),
                v.max_width_mm());
  }
  if (!m.suspect_reason.empty()) std::printf("      SUSPECT: %s\n", m.suspect_reason.c_str());
  if (!m.note.empty()) std::printf("      note: %s\n", m.note.c_str());
}

}  // namespace

SMC_CELL_COMMAND(part, 24) {
  auto* part = app.add_subcommand("part", "Parts: one part with its models, choice and jobs");
  part->require_subcommand(1);
  struct Args {
    std::string id, db;
  };
  auto a = std::make_shared<Args>();
  auto* show = part->add_subcommand(
      "show",
      "One part: its programmed cut, the models for it on each machine (provenance, validation,\n"
      "suspicion, fit), what a job of it would get now and why, its jobs and its history");
  show->add_option("ID", a->id, "Part id")->required();
  add_db_option(show, a->db);
  show->callback([a] {
    auto db = store::Store::open(a->db, store::OpenMode::kExisting);
    const auto p = db.part(a->id);
    if (!p) {
      throw Failure(2, "no part '" + a->id + "' in " + db.path() +
                           "; fix: see the ids with 'smc-cell catalog list part'");
    }
    std::printf("part %s  %s%s\n", p->id.c_str(), p->name.c_str(),
                p->retired_at_ms != 0 ? "  [retired]" : "");
    std::printf("  material %s, tool %s; %g mm wide (offset %g), %g mm long\n",
                p->material_id.c_str(), p->tool_id.empty() ? "(none)" : p->tool_id.c_str(),
                p->width_mm, p->offset_mm, p->length_mm);
    std::printf("  programmed cut: %g mm at %g mm/s, %g rpm\n", p->total_depth_mm, p->feedrate_mm_s,
                p->spindle_rpm);
    std::printf("  models\n");
    for (const auto& m : db.machines()) {
      if (m.retired_at_ms != 0) continue;
      const auto models = db.find_models(m.id, p->tool_id, p->material_id, p->id);
      std::printf("   on %s:%s\n", m.id.c_str(), models.empty() ? " none" : "");
      for (const auto& pm : models) print_model(pm);
    }
    // What the planner would choose for a job with the part's defaults, if
    // every machine's edge were up.
    if (!p->tool_id.empty() && p->retired_at_ms == 0) {
      store::Job job;
      job.id = "(a job of " + p->id + ")";
      job.spec.set_part_id(p->id);
      job.spec.set_tool_id(p->tool_id);
      job.spec.set_spindle_rpm(p->spindle_rpm);
      job.spec.set_feedrate_mm_s(p->feedrate_mm_s);
      job.spec.set_depth_mm(p->total_depth_mm);
      smc::cell::Selection sel;
      const auto in = smc::cell::bind_job(db, job, sel);
      std::printf("  a job now: %s%s\n    %s\n",
                  std::string(store::variant_name(sel.variant)).c_str(),
                  sel.variant == cfg::SMC_I ? (" on " + in.machine.id).c_str() : "",
                  sel.explanation.c_str());
    }
    std::printf("  jobs\n");
    int jobs = 0;
    for (const auto& j : db.jobs({.with_documents = true})) {
      if (j.spec.part_id() != p->id) continue;
      ++jobs;
      std::printf("    %-12s %-11s %-7s %-8s %s\n", j.id.c_str(),
                  std::string(store::state_name(j.state)).c_str(),
                  std::string(store::variant_name(j.variant)).c_str(),
                  j.machine_id.empty() ? "-" : j.machine_id.c_str(),
                  j.result ? ("chatter events " + std::to_string(j.result->chatter_events()) +
                              ", passes " + std::to_string(j.result->passes_completed()))
                                 .c_str()
                           : "");
    }
    if (jobs == 0) std::printf("    (none)\n");
    smc::cell::cli::print_history(db, "part", p->id);
  });
}
