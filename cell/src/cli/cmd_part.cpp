// smc-cell part show ID: one part as a cell engineer wants to see it — its
// programmed cut, the models the cell holds for it on each machine (their
// provenance, validation, suspicion and fit), what a job of it would get
// now and why, its jobs and its history.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>

#include "registry.hpp"
#include "smc/cell/candidates.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc_config.pb.h"

namespace {

using smc::cell::cli::add_db_option;
using smc::cell::cli::Failure;
namespace store = smc::cell::store;
namespace cfg = smc::config;

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

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

// The stability evidence of a part's cuts, per machine, tool and speed: the
// deepest chatter-free cut and the shallowest chatter bound the limit; where
// the machine has a milling model for the part, its time-domain critical
// depth is checked against them.
void print_evidence(store::Store& db, const store::Part& p) {
  const auto ev = db.stability_evidence(p.id);
  std::printf("  stability evidence%s\n", ev.empty() ? ": none yet (every cut records it)" : "");
  struct Bound {
    double stable = 0, chatter = 1e9, hz = 0;
    double stable_feed = 0, chatter_feed = 0;  // feed per tooth of those two cuts
    std::uint32_t revolutions = 0;
    std::set<std::string> jobs;
  };
  std::map<std::tuple<std::string, std::string, long>, Bound> bounds;
  for (const auto& e : ev) {
    auto& b = bounds[{e.machine_id, e.tool_id, std::lround(e.spindle_rpm)}];
    if (e.chatter && e.depth_mm < b.chatter) {
      b.chatter = e.depth_mm;
      b.hz = e.frequency_hz;
      b.chatter_feed = e.feed_per_tooth_mm;
    } else if (!e.chatter) {
      if (e.depth_mm > b.stable) b.stable_feed = e.feed_per_tooth_mm;
      b.stable = std::max(b.stable, e.depth_mm);
      b.revolutions += e.revolutions;
    }
    b.jobs.insert(e.job_id);
  }
  for (const auto& [key, b] : bounds) {
    const auto& [machine, tool, rpm] = key;
    std::printf("   on %s, tool %s, at %ld rpm (%zu job%s):\n", machine.c_str(), tool.c_str(), rpm,
                b.jobs.size(), b.jobs.size() == 1 ? "" : "s");
    const bool has_chatter = b.chatter < 1e9;
    if (b.stable > 0) {
      std::printf("     cut without chatter to %.2f mm (%u revolutions)\n", b.stable,
                  b.revolutions);
    }
    if (has_chatter) {
      std::printf("     chatter at %.2f mm%s\n", b.chatter,
                  b.hz > 0 ? (" (" + std::to_string(std::lround(b.hz)) + " Hz)").c_str() : "");
    }
    if (has_chatter && b.stable >= b.chatter) {
      std::printf(
          "     the evidence disagrees with itself (stable deeper than a chatter): the "
          "cuts differed in width or feed, or the machine changed\n");
    } else {
      std::printf("     so the stability limit lies %s\n",
                  has_chatter
                      ? (b.stable > 0 ? ("in (" + num(b.stable) + ", " + num(b.chatter) + "] mm")
                                      : ("at or below " + num(b.chatter) + " mm"))
                            .c_str()
                      : ("above " + num(b.stable) + " mm").c_str());
    }
    // The machine's milling model for the part, against the evidence.
    const auto t = db.tool(tool);
    for (const auto& m : db.find_models(machine, tool, p.material_id, p.id)) {
      if (m.kind != store::ModelKind::kMilling || m.retired_at_ms != 0 || !t) continue;
      cfg::MillingModel mm = m.milling;
      mm.mutable_cutter()->set_teeth(t->teeth);
      mm.mutable_cutter()->set_radius_mm(t->radius_mm);
      mm.mutable_cutter()->set_lead_angle_deg(t->lead_angle_deg);
      mm.mutable_workpiece()->set_width_mm(p.width_mm);
      mm.mutable_workpiece()->set_offset_mm(p.offset_mm);
      mm.mutable_workpiece()->set_length_mm(p.length_mm);
      // The model's limit at the feed of each bounding cut (with power-law
      // pressures the critical depth falls with the feed).
      try {
        const auto model = smc::machining::from_proto(mm, "milling_model");
        auto limit = [&](double feed) {
          const auto c = smc::machining::critical_depth_tds(model, static_cast<double>(rpm),
                                                            feed > 0 ? feed : 0.1);
          return c.bounded ? c.critical_depth_mm : 1e9;
        };
        auto depth = [](double d) { return d < 1e9 ? num(d) + " mm" : std::string("unbounded"); };
        if (has_chatter) {
          const double d = limit(b.chatter_feed);
          std::printf(
              "     model %s: critical depth %s at the chattering cut's %.4f mm/tooth: %s\n",
              m.id.c_str(), depth(d).c_str(), b.chatter_feed,
              d > b.chatter + 1e-6
                  ? ("CONTRADICTED: chatter at " + num(b.chatter) + " mm, below it").c_str()
                  : "consistent with the chatter");
        }
        if (b.stable > 0) {
          const double d = limit(b.stable_feed);
          std::printf(
              "     model %s: critical depth %s at the clean cut's %.4f mm/tooth: %s\n",
              m.id.c_str(), depth(d).c_str(), b.stable_feed,
              d < b.stable - 1e-6
                  ? ("CONTRADICTED: " + num(b.stable) + " mm was cut without chatter").c_str()
                  : "consistent with the clean cut");
        }
      } catch (const std::exception& e) {
        std::printf("     model %s: cannot be checked (%s)\n", m.id.c_str(), e.what());
      }
    }
  }
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
      "suspicion, fit), the stability evidence of its cuts (and each milling model checked\n"
      "against it), what a job of it would get now and why, its jobs and its history");
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
    print_evidence(db, *p);
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
