// smc-cell catalog apply|export|list|show|retire, smc-cell model
// validate|suspect: the shop's own machines, tools, materials, parts and
// models, from documents (cell/store/README.md, "Catalog documents").

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "registry.hpp"
#include "smc/cell/channel_notes.hpp"
#include "smc/cell/store/catalog_docs.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/frf.hpp"
#include "smc_config.pb.h"

namespace {

using smc::cell::cli::add_db_option;
using smc::cell::cli::Failure;
namespace store = smc::cell::store;

// Who is making the change: --author, else $SMC_AUTHOR, else the login name.
std::string author_or_default(const std::string& given) {
  if (!given.empty()) return given;
  if (const char* a = std::getenv("SMC_AUTHOR"); a != nullptr && *a != '\0') return a;
  if (const char* u = std::getenv("USER"); u != nullptr && *u != '\0') return u;
  return "uid " + std::to_string(::getuid());
}

const char* kKinds = "machine, tool, material, part, model";

bool known_kind(const std::string& k) {
  return k == "machine" || k == "tool" || k == "material" || k == "part" || k == "model";
}

// The entity as its document, or nullptr-like empty string when unknown.
std::string show_entity(store::Store& s, const std::string& kind, const std::string& id,
                        std::int64_t& retired) {
  smc::config::Catalog one;
  retired = 0;
  if (kind == "machine") {
    const auto m = s.machine(id);
    if (!m) return {};
    retired = m->retired_at_ms;
  } else if (kind == "tool") {
    const auto t = s.tool(id);
    if (!t) return {};
    retired = t->retired_at_ms;
  } else if (kind == "material") {
    const auto m = s.material(id);
    if (!m) return {};
    retired = m->retired_at_ms;
  } else if (kind == "part") {
    const auto p = s.part(id);
    if (!p) return {};
    retired = p->retired_at_ms;
  } else {
    const auto m = s.model(id);
    if (!m) return {};
    retired = m->retired_at_ms;
  }
  // The document form, from the export (in-use entities) or, for a retired
  // one, its row's fields are still in the database: show what export would.
  const auto all = store::export_catalog(s);
  const auto pick = [&](const auto& list) -> std::string {
    for (const auto& e : list) {
      if (e.id() == id) return smc::documents::to_textproto(e);
    }
    return "(retired: not exported)\n";
  };
  if (kind == "machine") return pick(all.machines());
  if (kind == "tool") return pick(all.tools());
  if (kind == "material") return pick(all.materials());
  if (kind == "part") return pick(all.parts());
  return pick(all.models());
}

// What module E would make of each machine's own wideband channel with the
// structures the cell has of that machine (the database's models and the
// documents' own): a note where the channel's filter hides a y mode's
// chatter (edge/CHATTER.md, "What the channel's filter costs E"). The
// record is accepted all the same: the sensor is what it is.
std::vector<std::string> channel_notes(store::Store& s, const store::CatalogDocuments& docs) {
  std::vector<std::string> notes;
  for (const auto& f : docs.machines) {
    const auto& d = f.doc;
    const auto w = store::machine_from_doc(d).wideband;
    if (w.is_default()) continue;
    std::vector<smc::cell::StructureOf> structures;
    const auto stored = s.find_models(d.id(), "", "", "");
    smc::cell::add_milling_structures(stored, structures);
    for (const auto& m : docs.models) {
      if (m.doc.machine_id() == d.id() && m.doc.has_milling()) {
        structures.push_back({m.doc.id(), &m.doc.milling().structure()});
      }
    }
    for (const auto& n : smc::cell::channel_notes(w, structures)) {
      notes.push_back("machine " + d.id() + " with the structure of model " + n.model_id + ": " +
                      n.text);
    }
  }
  return notes;
}

}  // namespace

SMC_CELL_COMMAND(catalog, 22) {
  auto* cat = app.add_subcommand(
      "catalog",
      "The cell's machines, tools, materials, parts and models as documents (smc.config.Catalog,\n"
      "textproto or JSON; the demo's are in cell/catalog): apply, export, list, show, retire");
  cat->require_subcommand(1);

  struct ApplyArgs {
    std::vector<std::string> paths;
    std::string db, author, reason = "catalog apply";
    bool dry_run = false;
  };
  auto a = std::make_shared<ApplyArgs>();
  auto* apply = cat->add_subcommand(
      "apply",
      "Check documents (files or folders) against each other and the database and write what\n"
      "they change, in one transaction, each change recorded with author and reason. Prints the\n"
      "changes (created, updated with the fields, unchanged). Idempotent. Refused as a whole,\n"
      "nothing written, when any document is wrong (file, field and fix are named). A note\n"
      "follows where a machine's wideband channel would hide a y mode's chatter from module E\n"
      "(its filter takes the mode more than 8 dB down, or the mode is above its Nyquist\n"
      "frequency), judged with the structures of that machine's models; the record is kept.");
  apply->add_option("PATH", a->paths, "Catalog files or folders")->required();
  add_db_option(apply, a->db);
  apply->add_flag("--dry-run", a->dry_run, "Check and show the changes; write nothing");
  apply->add_option("--author", a->author, "Who makes the change (default: $SMC_AUTHOR or $USER)");
  apply->add_option("--reason", a->reason, "Why, for the history")->capture_default_str();
  apply->callback([a] {
    auto s = store::Store::open(a->db, store::OpenMode::kExisting);
    std::vector<store::CatalogChange> changes;
    std::vector<std::string> notes;
    try {
      const auto docs = store::load_catalog(a->paths);
      changes = store::apply_catalog(
          s, docs,
          {.dry_run = a->dry_run, .author = author_or_default(a->author), .reason = a->reason});
      notes = channel_notes(s, docs);
    } catch (const store::CatalogError& e) {
      throw Failure(2, std::string(e.what()) + "\ncatalog apply: nothing written");
    }
    int n = 0;
    for (const auto& c : changes) {
      if (c.action == "unchanged") continue;
      ++n;
      std::printf("%s%-8s %s%s%s\n", a->dry_run ? "would be " : "", c.action.c_str(),
                  (c.kind + " " + c.id).c_str(), c.detail.empty() ? "" : ": ", c.detail.c_str());
    }
    std::printf("%d change%s%s, %zu unchanged\n", n, n == 1 ? "" : "s",
                a->dry_run ? " (dry run: nothing written)" : "",
                changes.size() - static_cast<size_t>(n));
    for (const auto& note : notes) std::printf("note: %s\n", note.c_str());
  });

  struct ExportArgs {
    std::string dir, db;
  };
  auto ex = std::make_shared<ExportArgs>();
  auto* exp = cat->add_subcommand(
      "export",
      "Write the catalog in use (retired entities left out) as documents: machines, tools,\n"
      "materials, parts and models .textproto in DIR, to keep under version control or apply\n"
      "to another cell");
  exp->add_option("DIR", ex->dir, "Folder to write (created)")->required();
  add_db_option(exp, ex->db);
  exp->callback([ex] {
    auto s = store::Store::open(ex->db, store::OpenMode::kExisting);
    for (const auto& f : store::write_catalog(store::export_catalog(s), ex->dir)) {
      std::printf("%s\n", f.c_str());
    }
  });

  struct ListArgs {
    std::string kind, db;
    bool retired = false;
  };
  auto l = std::make_shared<ListArgs>();
  auto* list = cat->add_subcommand("list", "The catalog, kind by kind (one line per entity)");
  list->add_option("KIND", l->kind, std::string("Only this kind: ") + kKinds);
  add_db_option(list, l->db);
  list->add_flag("--retired", l->retired, "Also list retired entities");
  list->callback([l] {
    if (!l->kind.empty() && !known_kind(l->kind)) {
      throw Failure(2, "unknown kind '" + l->kind + "' (known: " + kKinds + ")");
    }
    auto s = store::Store::open(l->db, store::OpenMode::kExisting);
    const auto want = [&](const char* k) { return l->kind.empty() || l->kind == k; };
    const auto mark = [&](std::int64_t r) { return r != 0 ? "  [retired]" : ""; };
    if (want("machine")) {
      for (const auto& m : s.machines()) {
        if (m.retired_at_ms != 0 && !l->retired) continue;
        // Its wideband channel (module E's) where the record gives one.
        const std::string channel = m.wideband.is_default()
                                        ? std::string()
                                        : "  [wideband " + store::channel_text(m.wideband) + "]";
        std::printf("machine  %-16s %7.1f W %6.1f mm/s %5.0f-%-5.0f rpm %-9s %s%s%s\n",
                    m.id.c_str(), m.max_spindle_power_w, m.max_feedrate_mm_s, m.min_spindle_rpm,
                    m.max_spindle_rpm, m.drive.c_str(), m.name.c_str(), channel.c_str(),
                    mark(m.retired_at_ms));
      }
    }
    if (want("tool")) {
      for (const auto& t : s.tools()) {
        if (t.retired_at_ms != 0 && !l->retired) continue;
        std::printf("tool     %-16s %u teeth, R %g mm, lead %g deg  %s%s\n", t.id.c_str(), t.teeth,
                    t.radius_mm, t.lead_angle_deg, t.name.c_str(), mark(t.retired_at_ms));
      }
    }
    if (want("material")) {
      for (const auto& m : s.materials()) {
        if (m.retired_at_ms != 0 && !l->retired) continue;
        std::printf("material %-16s %s%s\n", m.id.c_str(), m.name.c_str(), mark(m.retired_at_ms));
      }
    }
    if (want("part")) {
      for (const auto& p : s.parts()) {
        if (p.retired_at_ms != 0 && !l->retired) continue;
        std::printf("part     %-16s %s, tool %s, %g x %g mm, %g mm at %g mm/s, %g rpm  %s%s\n",
                    p.id.c_str(), p.material_id.c_str(), p.tool_id.c_str(), p.width_mm, p.length_mm,
                    p.total_depth_mm, p.feedrate_mm_s, p.spindle_rpm, p.name.c_str(),
                    mark(p.retired_at_ms));
      }
    }
    if (want("model")) {
      // find_models leaves retired ones out; list them from the export's
      // complement only when asked.
      for (const auto& m : s.find_models("", "", "", "")) {
        std::printf("model    %-26s %-13s %s, tool %s, %s%s, %s%s%s\n", m.id.c_str(),
                    std::string(store::kind_name(m.kind)).c_str(), m.machine_id.c_str(),
                    m.tool_id.c_str(), m.material_id.c_str(),
                    m.part_id.empty() ? "" : (", part " + m.part_id).c_str(),
                    m.validated ? "validated" : "not validated",
                    m.suspect_reason.empty() ? "" : ", SUSPECT: ", m.suspect_reason.c_str());
      }
    }
  });

  struct ShowArgs {
    std::string kind, id, db;
  };
  auto sh = std::make_shared<ShowArgs>();
  auto* show = cat->add_subcommand("show", "One entity as its document, and its history");
  show->add_option("KIND", sh->kind, kKinds)->required();
  show->add_option("ID", sh->id, "Its id")->required();
  add_db_option(show, sh->db);
  show->callback([sh] {
    if (!known_kind(sh->kind)) {
      throw Failure(2, "unknown kind '" + sh->kind + "' (known: " + kKinds + ")");
    }
    auto s = store::Store::open(sh->db, store::OpenMode::kExisting);
    std::int64_t retired = 0;
    const std::string doc = show_entity(s, sh->kind, sh->id, retired);
    if (doc.empty()) {
      throw Failure(2, "no " + sh->kind + " '" + sh->id + "' in " + s.path() +
                           "; fix: see the ids with 'smc-cell catalog list " + sh->kind + "'");
    }
    std::printf("%s %s%s\n", sh->kind.c_str(), sh->id.c_str(),
                retired != 0 ? ("  [retired " + store::format_time(retired) + "]").c_str() : "");
    if (sh->kind == "model") {
      const auto m = s.model(sh->id);
      if (!m->suspect_reason.empty()) std::printf("  SUSPECT: %s\n", m->suspect_reason.c_str());
    }
    std::printf("%s", doc.c_str());
    smc::cell::cli::print_history(s, sh->kind, sh->id);
  });

  struct RetireArgs {
    std::string kind, id, db, author, reason;
  };
  auto r = std::make_shared<RetireArgs>();
  auto* retire = cat->add_subcommand(
      "retire",
      "Retire an entity: it stays for the jobs that used it and the record (nothing is ever\n"
      "deleted); new jobs and plans refuse it; retired machines take no new jobs");
  retire->add_option("KIND", r->kind, kKinds)->required();
  retire->add_option("ID", r->id, "Its id")->required();
  retire->add_option("--reason", r->reason, "Why (recorded)")->required();
  retire->add_option("--author", r->author, "Who (default: $SMC_AUTHOR or $USER)");
  add_db_option(retire, r->db);
  retire->callback([r] {
    if (!known_kind(r->kind)) {
      throw Failure(2, "unknown kind '" + r->kind + "' (known: " + kKinds + ")");
    }
    auto s = store::Store::open(r->db, store::OpenMode::kExisting);
    try {
      s.retire(r->kind, r->id, author_or_default(r->author), r->reason);
    } catch (const store::StoreError& e) {
      throw Failure(2, e.what());
    }
    std::printf("%s %s retired\n", r->kind.c_str(), r->id.c_str());
  });
}

SMC_CELL_COMMAND(model, 23) {
  auto* model = app.add_subcommand(
      "model",
      "Process models: validate one with evidence, mark one suspect with a reason, or fit a\n"
      "structural model from a tap test");
  model->require_subcommand(1);
  struct Args {
    std::string id, db, author, text;
  };
  auto v = std::make_shared<Args>();
  auto* validate = model->add_subcommand(
      "validate",
      "Mark a model validated (the planner uses validated models for SMC I); clears a suspicion");
  validate->add_option("ID", v->id, "Model id")->required();
  validate->add_option("--evidence", v->text, "What validates it (recorded)")->required();
  validate->add_option("--author", v->author, "Who (default: $SMC_AUTHOR or $USER)");
  add_db_option(validate, v->db);
  validate->callback([v] {
    auto s = store::Store::open(v->db, store::OpenMode::kExisting);
    try {
      s.transaction([&] {
        s.set_model_validated(v->id, true);
        s.record_catalog_event("model", v->id, "validated", author_or_default(v->author), v->text);
      });
    } catch (const store::StoreError& e) {
      throw Failure(2, e.what());
    }
    std::printf("model %s validated\n", v->id.c_str());
  });
  auto u = std::make_shared<Args>();
  auto* suspect = model->add_subcommand(
      "suspect", "Mark a model suspect: it is listed but not used for SMC I until validated again");
  suspect->add_option("ID", u->id, "Model id")->required();
  suspect->add_option("--reason", u->text, "Why (recorded)")->required();
  suspect->add_option("--author", u->author, "Who (default: $SMC_AUTHOR or $USER)");
  add_db_option(suspect, u->db);
  suspect->callback([u] {
    auto s = store::Store::open(u->db, store::OpenMode::kExisting);
    try {
      s.transaction([&] {
        s.mark_model_suspect(u->id, u->text);
        s.record_catalog_event("model", u->id, "suspected", author_or_default(u->author), u->text);
      });
    } catch (const store::StoreError& e) {
      throw Failure(2, e.what());
    }
    std::printf("model %s marked suspect\n", u->id.c_str());
  });

  struct FitArgs {
    std::string csv, base, id, on = "tool", db, out, part, machine;
    int modes = 2;
  };
  auto f = std::make_shared<FitArgs>();
  auto* fit = model->add_subcommand(
      "fit-frf",
      "A structural model from a tap test: fit the modes of a measured frequency response\n"
      "(CSV: frequency_hz, then D_real_U, D_imag_U for D = x and/or y, U = m_per_n, mm_per_n or\n"
      "um_per_n) and write a catalog document of a new milling model: the base model with\n"
      "its structure along the measured directions replaced (not validated). Review it, then\n"
      "smc-cell catalog apply it");
  fit->add_option("CSV", f->csv, "The tap test's FRF")->required()->check(CLI::ExistingFile);
  fit->add_option("--base", f->base, "The milling model whose cutter, part and law it keeps")
      ->required();
  fit->add_option("--id", f->id, "The new model's id")->required();
  fit->add_option("--on", f->on, "What was tapped: tool or part")
      ->capture_default_str()
      ->check(CLI::IsMember({"tool", "part"}));
  fit->add_option("--modes", f->modes, "At most this many modes per direction")
      ->capture_default_str()
      ->check(CLI::Range(1, 6));
  fit->add_option("--part", f->part,
                  "The part the model is for (default: the base's). A model made for a part\n"
                  "the cell learns: its cuts validate it, or mark it suspect");
  fit->add_option("--machine", f->machine, "The machine tapped (default: the base's)");
  fit->add_option("--out", f->out, "Write the document here (default: standard output)");
  add_db_option(fit, f->db);
  fit->callback([f] {
    auto s = store::Store::open(f->db, store::OpenMode::kExisting);
    const auto catalog = store::export_catalog(s);
    const smc::config::CatalogModel* base = nullptr;
    for (const auto& m : catalog.models()) {
      if (m.id() == f->base) base = &m;
    }
    if (base == nullptr || !base->has_milling()) {
      throw Failure(2, "--base " + f->base + ": no milling model of that id in " + s.path() +
                           "; fix: see them with 'smc-cell catalog list model'");
    }
    std::map<std::string, smc::machining::Frf> frf;
    try {
      frf = smc::machining::read_frf_csv(f->csv);
    } catch (const std::runtime_error& e) {
      throw Failure(2, e.what());
    }
    smc::config::Catalog doc;
    auto* m = doc.add_models();
    *m = *base;
    m->set_id(f->id);
    if (!f->part.empty()) {
      if (!s.part(f->part)) {
        throw Failure(2, "--part " + f->part + ": no part of that id in " + s.path() +
                             "; fix: see them with 'smc-cell catalog list part'");
      }
      m->set_part_id(f->part);
    }
    if (!f->machine.empty()) {
      if (!s.machine(f->machine)) {
        throw Failure(2, "--machine " + f->machine + ": no machine of that id in " + s.path() +
                             "; fix: see them with 'smc-cell catalog list machine'");
      }
      m->set_machine_id(f->machine);
    }
    m->set_provenance(smc::config::PROVENANCE_IDENTIFIED);
    m->set_validated(false);
    auto* st = m->mutable_milling()->mutable_structure();
    std::string report;
    for (const auto& [dir, points] : frf) {
      if (dir != "x" && dir != "y") {
        throw Failure(2, f->csv + ": direction '" + dir +
                             "': the structure has x and y (the feed and its normal); fix: name "
                             "the columns x_... and y_...");
      }
      smc::machining::ModalFit r;
      try {
        r = smc::machining::fit_modes(points, f->modes);
      } catch (const std::invalid_argument& e) {
        throw Failure(2, f->csv + ": direction '" + dir + "': " + e.what());
      }
      auto* modes = f->on == "tool" ? (dir == "x" ? st->mutable_tool_x() : st->mutable_tool_y())
                                    : (dir == "x" ? st->mutable_part_x() : st->mutable_part_y());
      modes->Clear();
      char line[160];
      std::snprintf(line, sizeof line, "%s_%s: %zu mode%s, R^2 %.4f over %d points", f->on.c_str(),
                    dir.c_str(), r.modes.size(), r.modes.size() == 1 ? "" : "s", r.r_squared,
                    r.points);
      report += std::string(report.empty() ? "" : "; ") + line;
      std::fprintf(stderr, "%s\n", line);
      for (const auto& mode : r.modes) {
        auto* pm = modes->Add();
        pm->set_natural_frequency_rad_s(mode.natural_frequency_rad_s);
        pm->set_damping_ratio(mode.damping_ratio);
        pm->set_stiffness_n_per_mm(mode.stiffness_n_per_mm);
        std::fprintf(stderr, "  %8.1f Hz  zeta %.4f  k %.0f N/mm\n",
                     mode.natural_frequency_rad_s / (2 * 3.141592653589793), mode.damping_ratio,
                     mode.stiffness_n_per_mm);
      }
    }
    m->set_note("structure from the tap test " + std::filesystem::path(f->csv).filename().string() +
                " (" + report + "); cutter, part and cutting law from " + f->base);
    const std::string text =
        "# proto-file: idl/smc_config.proto\n"
        "# proto-message: smc.config.Catalog\n" +
        smc::documents::to_textproto(doc);
    if (f->out.empty()) {
      std::fputs(text.c_str(), stdout);
    } else {
      std::ofstream(f->out) << text;
      std::fprintf(stderr, "wrote %s: review it, then smc-cell catalog apply %s\n", f->out.c_str(),
                   f->out.c_str());
    }
  });
}
