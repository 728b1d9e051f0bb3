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
#include <vector>

#include "registry.hpp"
#include "smc/cell/candidates.hpp"
#include "smc/cell/learning.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/common/svg_plot.hpp"
#include "smc/supervision/parameters.hpp"
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

void print_model(store::Store& db, const store::ProcessModel& m) {
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
  // What the cell's learning did with it: each check on a later run, and
  // its validation or suspicion with the evidence.
  const auto history = db.history("model", m.id);
  for (const auto& e : history) {
    if (e.action != "checked" && e.action != "validated" && e.action != "suspected") continue;
    std::printf("      %s %s%s: %s\n", store::format_time(e.time_ms).c_str(), e.action.c_str(),
                e.action == "checked" ? (" (" + e.detail + ")").c_str() : "", e.reason.c_str());
  }
  if (!m.validated && m.provenance == cfg::PROVENANCE_FITTED &&
      m.kind == store::ModelKind::kForceProcess) {
    const smc::cell::LearningPolicy policy;
    std::printf("      validation: %d of %d runs in a row predicted within %.0f %%\n",
                smc::cell::passed_in_a_row(history), policy.runs, policy.within_pct);
  }
}

// What module E gets on each machine for a job of the part that brings no
// structure of its own (SMC II, SMC II+; cell/README.md, "Module E's
// structure"), and what would make it better: a structure that is the
// machine's own from a tap test, and the machine's wideband channel.
void print_module_e(store::Store& db, const store::Job& job) {
  std::printf("  module E, where the plan brings no structure\n");
  for (const auto& m : db.machines()) {
    if (m.retired_at_ms != 0) continue;
    const auto s = smc::cell::structure_model(db, job, m.id);
    std::string line;
    if (!s) {
      line = "no structure of " + m.id + " with tool " + job.spec.tool_id() +
             ": E judges the force spectrum alone; a tap test (`smc-cell model fit-frf`) "
             "gives it the vibration estimate";
    } else {
      const bool measured =
          s->provenance == cfg::PROVENANCE_IDENTIFIED || s->provenance == cfg::PROVENANCE_FITTED;
      line = "the structure of model " + s->id + " (" +
             std::string(store::provenance_name(s->provenance)) +
             (s->suspect_reason.empty() ? "" : ", suspect") + ")";
      if (!s->part_id.empty() && s->part_id != job.spec.part_id()) {
        line += ", the part's modes being part " + s->part_id + "'s";
      }
      if (!measured) {
        line +=
            "; a tap test of this machine (`smc-cell model fit-frf`) gives E its own (on the "
            "mismatched mill a handbook structure read q 9-16 % low: edge/CHATTER.md, \"The "
            "structure E is given\")";
      }
    }
    if (!m.wideband.is_default()) {
      line += "; its wideband channel " + store::channel_text(m.wideband);
      // What that channel hides of the structure E would get.
      if (s) {
        const auto w = smc::supervision::wideband_channel_warning(
            m.wideband.rate_hz(), m.wideband.cutoff_hz, m.wideband.order(), s->milling.structure());
        if (!w.empty()) line += "; warning: " + w;
      }
    }
    std::printf("   on %s: %s\n", m.id.c_str(), line.c_str());
  }
}

// The stability evidence of a part's cuts, per machine, tool and speed: the
// deepest chatter-free cut and the shallowest chatter bound the limit; where
// the machine has a milling model for the part, its time-domain critical
// depth is checked against them (the same check the cell makes after each
// job, smc/cell/learning.hpp).
void print_evidence(store::Store& db, const store::Part& p) {
  const auto ev = db.stability_evidence(p.id);
  std::printf("  stability evidence%s\n", ev.empty() ? ": none yet (every cut records it)" : "");
  for (const auto& b : smc::cell::stability_bounds(ev)) {
    std::printf("   on %s, tool %s, at %ld rpm (%zu job%s):\n", b.machine_id.c_str(),
                b.tool_id.c_str(), b.rpm, b.jobs.size(), b.jobs.size() == 1 ? "" : "s");
    if (b.stable_mm > 0) {
      std::printf("     cut without chatter to %.2f mm (%u revolutions)\n", b.stable_mm,
                  b.revolutions);
    }
    if (b.has_chatter()) {
      std::printf("     chatter at %.2f mm%s\n", b.chatter_mm,
                  b.chatter_hz > 0
                      ? (" (" + std::to_string(std::lround(b.chatter_hz)) + " Hz)").c_str()
                      : "");
    }
    if (b.disagrees()) {
      std::printf(
          "     the evidence disagrees with itself (stable deeper than a chatter): the "
          "cuts differed in width or feed, or the machine changed\n");
    } else {
      std::printf(
          "     so the stability limit lies %s\n",
          b.has_chatter()
              ? (b.stable_mm > 0 ? ("in (" + num(b.stable_mm) + ", " + num(b.chatter_mm) + "] mm")
                                 : ("at or below " + num(b.chatter_mm) + " mm"))
                    .c_str()
              : ("above " + num(b.stable_mm) + " mm").c_str());
    }
    // The machine's milling models for the part, against the evidence.
    const auto t = db.tool(b.tool_id);
    if (!t) continue;
    for (const auto& m : db.find_models(b.machine_id, b.tool_id, p.material_id, p.id)) {
      if (m.kind != store::ModelKind::kMilling || m.retired_at_ms != 0) continue;
      try {
        const auto c = smc::cell::check_against(smc::cell::for_part(m, *t, p), b);
        auto depth = [](double d) {
          return d < smc::cell::BoundCheck::kUnbounded ? num(d) + " mm" : std::string("unbounded");
        };
        if (b.has_chatter()) {
          std::printf(
              "     model %s: critical depth %s at the chattering cut's %.4f mm/tooth: %s\n",
              m.id.c_str(), depth(c.critical_at_chatter_mm).c_str(), b.chatter_feed_mm,
              c.contradicted_by_chatter
                  ? ("CONTRADICTED: chatter at " + num(b.chatter_mm) + " mm, below it").c_str()
                  : "consistent with the chatter");
        }
        if (b.stable_mm > 0) {
          std::printf(
              "     model %s: critical depth %s at the clean cut's %.4f mm/tooth: %s\n",
              m.id.c_str(), depth(c.critical_at_stable_mm).c_str(), b.stable_feed_mm,
              c.contradicted_by_stable
                  ? ("CONTRADICTED: " + num(b.stable_mm) + " mm was cut without chatter").c_str()
                  : "consistent with the clean cut");
        }
      } catch (const std::exception& e) {
        std::printf("     model %s: cannot be checked (%s)\n", m.id.c_str(), e.what());
      }
    }
  }
}

// The part's runs, oldest first: what each got and how it went.
struct Run {
  std::string job, state, variant, machine;
  double cycle_s = NAN, overshoot_pct = NAN;
  int chatter = -1, passes = -1;
};

std::vector<Run> runs_of(store::Store& db, const store::Part& p) {
  std::vector<Run> out;
  for (const auto& j : db.jobs({.with_documents = true})) {
    if (j.spec.part_id() != p.id) continue;
    Run r{j.id, std::string(store::state_name(j.state)),
          std::string(store::variant_name(j.variant)), j.machine_id.empty() ? "-" : j.machine_id};
    if (j.result) {
      r.cycle_s = j.result->cycle_time_s();
      if (j.result->force_reference_n() > 0) r.overshoot_pct = j.result->overshoot_pct();
      r.chatter = static_cast<int>(j.result->chatter_events());
      r.passes = static_cast<int>(j.result->passes_completed());
    }
    out.push_back(std::move(r));
  }
  return out;
}

// Cycle time, overshoot and chatter events per run, with the runs that
// were promoted to SMC I marked.
void plot_runs(const std::vector<Run>& runs, const store::Part& p, const std::string& path) {
  smc::plot::Figure fig("part " + p.id + ": its runs");
  fig.x_axis().label = "run";
  fig.y_axis().label = "cycle time (s) / overshoot (%) / chatter events x 10";
  fig.y_axis().include_zero = true;
  std::vector<double> n, cycle, overshoot, chatter;
  std::string last_variant;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& r = runs[i];
    if (!std::isfinite(r.cycle_s)) continue;
    const double k = static_cast<double>(i + 1);
    n.push_back(k);
    cycle.push_back(r.cycle_s);
    overshoot.push_back(r.overshoot_pct);
    chatter.push_back(10.0 * r.chatter);
    if (!last_variant.empty() && r.variant != last_variant) fig.add_vertical(k - 0.5, r.variant);
    last_variant = r.variant;
  }
  // A series' reference is valid until the next add: style each as it comes.
  fig.add_line("cycle time (s)", n, cycle).style = smc::plot::Style::line_and_markers;
  fig.add_line("overshoot (%)", n, overshoot).style = smc::plot::Style::line_and_markers;
  fig.add_line("chatter events x 10", n, chatter).style = smc::plot::Style::line_and_markers;
  fig.write(path);
}

}  // namespace

SMC_CELL_COMMAND(part, 24) {
  auto* part = app.add_subcommand("part", "Parts: one part with its models, choice and jobs");
  part->require_subcommand(1);
  struct Args {
    std::string id, db, plot;
  };
  auto a = std::make_shared<Args>();
  auto* show = part->add_subcommand(
      "show",
      "One part: its programmed cut, the models for it on each machine (provenance, validation,\n"
      "suspicion, fit), the stability evidence of its cuts (and each milling model checked\n"
      "against it), what a job of it would get now and why, the structure and channel module E\n"
      "gets on each machine (and where a tap test would give it better), its jobs and its\n"
      "history");
  show->add_option("ID", a->id, "Part id")->required();
  show->add_option("--plot", a->plot,
                   "Also plot its runs (cycle time, overshoot, chatter events; the change\n"
                   "of supervisor marked) to this SVG file");
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
      for (const auto& pm : models) print_model(db, pm);
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
      print_module_e(db, job);
    }
    print_evidence(db, *p);
    const auto runs = runs_of(db, *p);
    std::printf("  jobs%s\n", runs.empty() ? ": none" : "");
    if (!runs.empty()) {
      std::printf("    %-3s %-12s %-11s %-7s %-8s %9s %10s %8s %7s\n", "run", "job", "state",
                  "variant", "machine", "cycle (s)", "overshoot", "chatter", "passes");
    }
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const auto& r = runs[i];
      auto f = [](double v, const char* unit) {
        char b[32];
        std::snprintf(b, sizeof b, "%.1f%s", v, unit);
        return std::isfinite(v) ? std::string(b) : std::string("-");
      };
      std::printf("    %-3zu %-12s %-11s %-7s %-8s %9s %10s %8s %7s\n", i + 1, r.job.c_str(),
                  r.state.c_str(), r.variant.c_str(), r.machine.c_str(), f(r.cycle_s, "").c_str(),
                  f(r.overshoot_pct, " %").c_str(),
                  r.chatter < 0 ? "-" : std::to_string(r.chatter).c_str(),
                  r.passes < 0 ? "-" : std::to_string(r.passes).c_str());
    }
    if (!a->plot.empty()) {
      plot_runs(runs, *p, a->plot);
      std::printf("  plot of its runs: %s\n", a->plot.c_str());
    }
    smc::cell::cli::print_history(db, "part", p->id);
  });
}
