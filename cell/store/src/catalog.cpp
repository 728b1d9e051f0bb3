// Machines, tools, materials, parts and process models.

#include <array>
#include <cmath>
#include <cstdio>

#include "ids.hpp"
#include "smc/cell/store/store.hpp"
#include "sqlite.hpp"

namespace smc::cell::store {

using detail::Blob;
using detail::or_null;
using detail::Stmt;

namespace detail {

std::vector<std::string> ids(sqlite3* db, const std::string& file, const char* sql) {
  Stmt s(db, file, sql);
  std::vector<std::string> out;
  while (s.step()) out.push_back(s.text(0));
  return out;
}

std::string unknown_ref(std::string_view what, const std::string& value,
                        const std::vector<std::string>& known) {
  std::string s = "unknown " + std::string(what) + " '" + value + "' (known: ";
  if (known.empty()) s += "none";
  for (std::size_t i = 0; i < known.size(); ++i) s += (i > 0 ? ", " : "") + known[i];
  return s + ")";
}

std::string next_id(sqlite3* db, const std::string& file, const std::string& series,
                    const char* exists_sql) {
  // The counter only grows, and an id someone chose by hand is skipped, so a
  // generated id is never handed out twice. Rolled back with the caller's
  // transaction: a number whose job was refused was never visible.
  for (;;) {
    Stmt(db, file,
         "INSERT INTO id_counters (name, last) VALUES (?, 1) "
         "ON CONFLICT (name) DO UPDATE SET last = last + 1")
        .bind(series)
        .run();
    Stmt get(db, file, "SELECT last FROM id_counters WHERE name = ?");
    get.bind(series).step();
    std::array<char, 48> buf{};
    std::snprintf(buf.data(), buf.size(), "-%06lld", static_cast<long long>(get.int64(0)));
    std::string id = series + buf.data();
    Stmt taken(db, file, exists_sql);
    if (!taken.bind(id).step()) return id;
  }
}

}  // namespace detail

namespace {

const char* const kMachineCols =
    "SELECT id, name, max_spindle_power_w, max_feedrate_mm_s, max_spindle_rpm, min_spindle_rpm, "
    "drive, COALESCE(retired_at_ms, 0), wideband_samples_per_tick, wideband_cutoff_hz, "
    "wideband_filter_order, wideband_noise_rms_n FROM machines ";
const char* const kToolCols =
    "SELECT id, name, teeth, radius_mm, lead_angle_deg, COALESCE(retired_at_ms, 0) FROM tools ";
const char* const kMaterialCols = "SELECT id, name, COALESCE(retired_at_ms, 0) FROM materials ";
const char* const kPartCols =
    "SELECT id, name, material_id, COALESCE(tool_id, ''), width_mm, offset_mm, length_mm, "
    "total_depth_mm, feedrate_mm_s, spindle_rpm, COALESCE(retired_at_ms, 0), "
    "speed_change_allowed FROM parts ";
const char* const kModelCols =
    "SELECT id, kind, machine_id, tool_id, material_id, COALESCE(part_id, ''), provenance, "
    "validated, document, fit, note, created_at_ms, suspect_reason, validity, "
    "COALESCE(retired_at_ms, 0) FROM process_models ";

Machine read_machine(const Stmt& s) {
  return Machine{s.text(0),
                 s.text(1),
                 s.real(2),
                 s.real(3),
                 s.real(4),
                 s.real(5),
                 s.text(6),
                 s.int64(7),
                 WidebandChannel{static_cast<std::uint32_t>(s.int64(8)), s.real(9),
                                 static_cast<std::uint32_t>(s.int64(10)), s.real(11)}};
}
Tool read_tool(const Stmt& s) {
  return Tool{s.text(0), s.text(1), static_cast<std::uint32_t>(s.int64(2)),
              s.real(3), s.real(4), s.int64(5)};
}
Material read_material(const Stmt& s) { return Material{s.text(0), s.text(1), s.int64(2)}; }
Part read_part(const Stmt& s) {
  return Part{s.text(0), s.text(1), s.text(2), s.text(3), s.real(4),   s.real(5),
              s.real(6), s.real(7), s.real(8), s.real(9), s.int64(10), s.int64(11) != 0};
}

ProcessModel read_model(const Stmt& s, const std::string& file) {
  ProcessModel m;
  m.id = s.text(0);
  m.kind = static_cast<ModelKind>(s.int64(1));
  m.machine_id = s.text(2);
  m.tool_id = s.text(3);
  m.material_id = s.text(4);
  m.part_id = s.text(5);
  m.provenance = static_cast<smc::config::Provenance>(s.int64(6));
  m.validated = s.int64(7) != 0;
  const std::string what = "process_models '" + m.id + "'";
  if (m.kind == ModelKind::kForceProcess) {
    detail::deserialize(s.blob(8), m.force, file, what + " document");
  } else {
    detail::deserialize(s.blob(8), m.milling, file, what + " document");
  }
  if (!s.is_null(9)) detail::deserialize(s.blob(9), m.fit, file, what + " fit");
  m.note = s.text(10);
  m.created_at_ms = s.int64(11);
  m.suspect_reason = s.text(12);
  if (!s.is_null(13)) detail::deserialize(s.blob(13), m.validity, file, what + " validity");
  m.retired_at_ms = s.int64(14);
  return m;
}

template <class T, class Read>
std::vector<T> read_all(Stmt& s, Read read) {
  std::vector<T> out;
  while (s.step()) out.push_back(read(s));
  return out;
}

template <class T, class Read>
std::optional<T> read_one(Stmt& s, Read read) {
  if (!s.step()) return std::nullopt;
  return read(s);
}

}  // namespace

// ------------------------------------------------------------------ catalog --

void Store::put_machine(const Machine& m) {
  Stmt(db_.get(), path_,
       "INSERT INTO machines (id, name, max_spindle_power_w, max_feedrate_mm_s, max_spindle_rpm, "
       "min_spindle_rpm, drive, wideband_samples_per_tick, wideband_cutoff_hz, "
       "wideband_filter_order, wideband_noise_rms_n) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
       "ON CONFLICT (id) DO UPDATE SET "
       "name = excluded.name, max_spindle_power_w = excluded.max_spindle_power_w, "
       "max_feedrate_mm_s = excluded.max_feedrate_mm_s, "
       "max_spindle_rpm = excluded.max_spindle_rpm, min_spindle_rpm = excluded.min_spindle_rpm, "
       "drive = excluded.drive, wideband_samples_per_tick = excluded.wideband_samples_per_tick, "
       "wideband_cutoff_hz = excluded.wideband_cutoff_hz, "
       "wideband_filter_order = excluded.wideband_filter_order, "
       "wideband_noise_rms_n = excluded.wideband_noise_rms_n")
      .bind(m.id, m.name, m.max_spindle_power_w, m.max_feedrate_mm_s, m.max_spindle_rpm,
            m.min_spindle_rpm, m.drive.empty() ? std::string("simulated") : m.drive,
            m.wideband.samples_per_tick, m.wideband.cutoff_hz, m.wideband.filter_order,
            m.wideband.noise_rms_n)
      .run();
}

void Store::put_tool(const Tool& t) {
  Stmt(db_.get(), path_,
       "INSERT INTO tools (id, name, teeth, radius_mm, lead_angle_deg) VALUES (?, ?, ?, ?, ?) "
       "ON CONFLICT (id) DO UPDATE SET name = excluded.name, teeth = excluded.teeth, "
       "radius_mm = excluded.radius_mm, lead_angle_deg = excluded.lead_angle_deg")
      .bind(t.id, t.name, t.teeth, t.radius_mm, t.lead_angle_deg)
      .run();
}

void Store::put_material(const Material& m) {
  Stmt(db_.get(), path_,
       "INSERT INTO materials (id, name) VALUES (?, ?) "
       "ON CONFLICT (id) DO UPDATE SET name = excluded.name")
      .bind(m.id, m.name)
      .run();
}

void Store::put_part(const Part& p) {
  const auto prefix = path_ + ": part '" + p.id + "': ";
  if (!material(p.material_id)) {
    throw StoreError(
        prefix + "material_id: " +
        detail::unknown_ref("material", p.material_id,
                            detail::ids(db_.get(), path_, "SELECT id FROM materials ORDER BY id")));
  }
  if (!p.tool_id.empty() && !tool(p.tool_id)) {
    throw StoreError(
        prefix + "tool_id: " +
        detail::unknown_ref("tool", p.tool_id,
                            detail::ids(db_.get(), path_, "SELECT id FROM tools ORDER BY id")));
  }
  Stmt(db_.get(), path_,
       "INSERT INTO parts (id, name, material_id, tool_id, width_mm, offset_mm, length_mm, "
       "total_depth_mm, feedrate_mm_s, spindle_rpm, speed_change_allowed) "
       "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
       "ON CONFLICT (id) DO UPDATE SET name = excluded.name, "
       "material_id = excluded.material_id, tool_id = excluded.tool_id, "
       "width_mm = excluded.width_mm, offset_mm = excluded.offset_mm, "
       "length_mm = excluded.length_mm, total_depth_mm = excluded.total_depth_mm, "
       "feedrate_mm_s = excluded.feedrate_mm_s, spindle_rpm = excluded.spindle_rpm, "
       "speed_change_allowed = excluded.speed_change_allowed")
      .bind(p.id, p.name, p.material_id, or_null(p.tool_id), p.width_mm, p.offset_mm, p.length_mm,
            p.total_depth_mm, p.feedrate_mm_s, p.spindle_rpm,
            static_cast<std::int64_t>(p.speed_change_allowed ? 1 : 0))
      .run();
}

std::vector<Machine> Store::machines() {
  Stmt s(db_.get(), path_, std::string(kMachineCols) + "ORDER BY id");
  return read_all<Machine>(s, read_machine);
}
std::vector<Tool> Store::tools() {
  Stmt s(db_.get(), path_, std::string(kToolCols) + "ORDER BY id");
  return read_all<Tool>(s, read_tool);
}
std::vector<Material> Store::materials() {
  Stmt s(db_.get(), path_, std::string(kMaterialCols) + "ORDER BY id");
  return read_all<Material>(s, read_material);
}
std::vector<Part> Store::parts() {
  Stmt s(db_.get(), path_, std::string(kPartCols) + "ORDER BY id");
  return read_all<Part>(s, read_part);
}

std::optional<Machine> Store::machine(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kMachineCols) + "WHERE id = ?");
  return read_one<Machine>(s.bind(id), read_machine);
}
std::optional<Tool> Store::tool(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kToolCols) + "WHERE id = ?");
  return read_one<Tool>(s.bind(id), read_tool);
}
std::optional<Material> Store::material(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kMaterialCols) + "WHERE id = ?");
  return read_one<Material>(s.bind(id), read_material);
}
std::optional<Part> Store::part(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kPartCols) + "WHERE id = ?");
  return read_one<Part>(s.bind(id), read_part);
}

// ------------------------------------------------------------------- models --

std::string Store::add_model(const ProcessModel& m) {
  // Checks and insert in one write transaction: the references cannot
  // vanish between the check and the insert.
  detail::Tx tx(db_.get(), path_);
  std::vector<std::string> problems;
  const auto known = [&](const char* sql) { return detail::ids(db_.get(), path_, sql); };
  if (m.kind != ModelKind::kForceProcess && m.kind != ModelKind::kMilling) {
    problems.push_back("kind: must be force-process (1) or milling (2)");
  }
  if (!machine(m.machine_id)) {
    problems.push_back(
        "machine_id: " +
        detail::unknown_ref("machine", m.machine_id, known("SELECT id FROM machines ORDER BY id")));
  }
  if (!tool(m.tool_id)) {
    problems.push_back(
        "tool_id: " +
        detail::unknown_ref("tool", m.tool_id, known("SELECT id FROM tools ORDER BY id")));
  }
  if (!material(m.material_id)) {
    problems.push_back("material_id: " +
                       detail::unknown_ref("material", m.material_id,
                                           known("SELECT id FROM materials ORDER BY id")));
  }
  if (!m.part_id.empty()) {
    const auto p = part(m.part_id);
    if (!p) {
      problems.push_back(
          "part_id: " +
          detail::unknown_ref("part", m.part_id, known("SELECT id FROM parts ORDER BY id")));
    } else if (p->material_id != m.material_id) {
      problems.push_back("part_id: part '" + m.part_id + "' is made of '" + p->material_id +
                         "', not '" + m.material_id + "'");
    }
  }
  if (m.provenance < smc::config::PROVENANCE_UNSPECIFIED ||
      m.provenance > smc::config::PROVENANCE_IDENTIFIED) {
    problems.push_back("provenance: not a smc.config.Provenance value");
  }
  if (m.kind == ModelKind::kForceProcess &&
      !(std::isfinite(m.force.k_kn()) && m.force.k_kn() > 0 && std::isfinite(m.force.beta()) &&
        std::isfinite(m.force.alpha()))) {
    problems.push_back("force: k_kn must be > 0 and beta, alpha finite");
  }
  if (!problems.empty()) {
    std::string msg = path_ + ": add_model '" + m.id + "':";
    for (const auto& p : problems) msg += "\n  " + p;
    throw StoreError(msg);
  }

  // The document carries the row's provenance and validation too, so it is
  // complete when it travels on its own (to an edge, to the browser).
  std::string document;
  if (m.kind == ModelKind::kForceProcess) {
    smc::config::ForceProcessModel doc = m.force;
    doc.set_provenance(m.provenance);
    doc.set_validated(m.validated);
    if (m.fit.ByteSizeLong() > 0) *doc.mutable_fit() = m.fit;
    document = detail::serialize(doc, "force-process model");
  } else {
    smc::config::MillingModel doc = m.milling;
    doc.set_provenance(m.provenance);
    doc.set_validated(m.validated);
    document = detail::serialize(doc, "milling model");
  }
  std::optional<Blob> fit;
  if (m.fit.ByteSizeLong() > 0) fit = Blob{detail::serialize(m.fit, "fit statistics")};

  std::string id = m.id;
  const char* exists = "SELECT 1 FROM process_models WHERE id = ?";
  if (id.empty()) {
    id = detail::next_id(db_.get(), path_, "model", exists);
  } else if (Stmt(db_.get(), path_, exists).bind(id).step()) {
    throw StoreError(path_ + ": add_model: a model '" + id +
                     "' exists already; models are never replaced, leave id empty for a new one");
  }
  Stmt ins(db_.get(), path_,
           "INSERT INTO process_models (id, kind, machine_id, tool_id, material_id, part_id, "
           "provenance, validated, document, fit, note, created_at_ms, suspect_reason, validity) "
           "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  std::optional<Blob> validity;
  if (m.validity.ByteSizeLong() > 0) {
    validity = Blob{detail::serialize(m.validity, "validity range")};
  }
  ins.bind(id, static_cast<int>(m.kind), m.machine_id, m.tool_id, m.material_id, or_null(m.part_id),
           static_cast<int>(m.provenance), m.validated, Blob{document}, fit, m.note,
           detail::now_ms(), m.suspect_reason, validity);
  ins.run();
  tx.commit();
  return id;
}

std::optional<ProcessModel> Store::model(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kModelCols) + "WHERE id = ?");
  if (!s.bind(id).step()) return std::nullopt;
  return read_model(s, path_);
}

void Store::set_model_validated(const std::string& id, bool validated) {
  detail::Tx tx(db_.get(), path_);
  auto m = model(id);
  if (!m) {
    throw StoreError(path_ + ": set_model_validated: unknown model '" + id + "'");
  }
  std::string document;
  if (m->kind == ModelKind::kForceProcess) {
    m->force.set_validated(validated);
    document = detail::serialize(m->force, "force-process model");
  } else {
    m->milling.set_validated(validated);
    document = detail::serialize(m->milling, "milling model");
  }
  // Validating a model again clears a suspicion.
  Stmt(db_.get(), path_,
       "UPDATE process_models SET validated = ?1, document = ?2, "
       "suspect_reason = CASE WHEN ?1 THEN '' ELSE suspect_reason END WHERE id = ?3")
      .bind(validated, Blob{document}, id)
      .run();
  tx.commit();
}

void Store::mark_model_suspect(const std::string& id, const std::string& reason) {
  if (reason.empty()) {
    throw StoreError(path_ + ": mark_model_suspect: model '" + id + "': the reason is empty");
  }
  detail::Tx tx(db_.get(), path_);
  Stmt(db_.get(), path_, "UPDATE process_models SET suspect_reason = ? WHERE id = ?")
      .bind(reason, id)
      .run();
  if (sqlite3_changes(db_.get()) == 0) {
    throw StoreError(path_ + ": mark_model_suspect: unknown model '" + id + "'");
  }
  tx.commit();
}

std::vector<ProcessModel> Store::find_models(const std::string& machine_id,
                                             const std::string& tool_id,
                                             const std::string& material_id,
                                             const std::string& part_id) {
  Stmt s(db_.get(), path_,
         std::string(kModelCols) +
             "WHERE retired_at_ms IS NULL AND (?1 = '' OR machine_id = ?1) AND (?2 = '' OR tool_id "
             "= ?2) "
             "AND (?3 = '' OR material_id = ?3) "
             "AND (?4 = '' OR part_id = ?4 OR part_id IS NULL) "
             "ORDER BY (part_id IS NULL), validated DESC, (suspect_reason != ''), "
             "CASE provenance WHEN 3 THEN 0 WHEN 2 THEN 1 WHEN 1 THEN 2 ELSE 3 END, "
             "created_at_ms DESC, rowid DESC");
  s.bind(machine_id, tool_id, material_id, part_id);
  std::vector<ProcessModel> out;
  while (s.step()) out.push_back(read_model(s, path_));
  return out;
}

// ------------------------------------------------------------------ history --

void Store::record_catalog_event(const std::string& kind, const std::string& entity_id,
                                 const std::string& action, const std::string& author,
                                 const std::string& reason, const std::string& detail) {
  Stmt(db_.get(), path_,
       "INSERT INTO catalog_history (time_ms, author, kind, entity_id, action, reason, detail) "
       "VALUES (?, ?, ?, ?, ?, ?, ?)")
      .bind(detail::now_ms(), author.empty() ? std::string("unknown") : author, kind, entity_id,
            action, reason, detail)
      .run();
}

void Store::add_stability_evidence(const StabilityEvidence& e) {
  Stmt(db_.get(), path_,
       "INSERT INTO stability_evidence (time_ms, part_id, machine_id, tool_id, job_id, "
       "spindle_rpm, depth_mm, width_mm, feed_per_tooth_mm, chatter, frequency_hz, revolutions) "
       "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(detail::now_ms(), e.part_id, e.machine_id, e.tool_id, e.job_id, e.spindle_rpm,
            e.depth_mm, e.width_mm, e.feed_per_tooth_mm, e.chatter ? 1 : 0, e.frequency_hz,
            static_cast<std::int64_t>(e.revolutions))
      .run();
}

std::vector<StabilityEvidence> Store::stability_evidence(const std::string& part_id) {
  Stmt s(db_.get(), path_,
         "SELECT seq, time_ms, part_id, machine_id, tool_id, job_id, spindle_rpm, depth_mm, "
         "width_mm, feed_per_tooth_mm, chatter, frequency_hz, revolutions FROM stability_evidence "
         "WHERE part_id = ? ORDER BY seq");
  s.bind(part_id);
  std::vector<StabilityEvidence> out;
  while (s.step()) {
    StabilityEvidence e;
    e.seq = s.int64(0);
    e.time_ms = s.int64(1);
    e.part_id = s.text(2);
    e.machine_id = s.text(3);
    e.tool_id = s.text(4);
    e.job_id = s.text(5);
    e.spindle_rpm = s.real(6);
    e.depth_mm = s.real(7);
    e.width_mm = s.real(8);
    e.feed_per_tooth_mm = s.real(9);
    e.chatter = s.int64(10) != 0;
    e.frequency_hz = s.real(11);
    e.revolutions = static_cast<std::uint32_t>(s.int64(12));
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<CatalogEvent> Store::history(const std::string& kind, const std::string& entity_id) {
  Stmt s(
      db_.get(), path_,
      "SELECT seq, time_ms, author, kind, entity_id, action, reason, detail FROM catalog_history "
      "WHERE (?1 = '' OR kind = ?1) AND (?2 = '' OR entity_id = ?2) ORDER BY seq");
  s.bind(kind, entity_id);
  std::vector<CatalogEvent> out;
  while (s.step()) {
    out.push_back(
        {s.int64(0), s.int64(1), s.text(2), s.text(3), s.text(4), s.text(5), s.text(6), s.text(7)});
  }
  return out;
}

namespace {

const char* table_of(const std::string& kind) {
  if (kind == "machine") return "machines";
  if (kind == "tool") return "tools";
  if (kind == "material") return "materials";
  if (kind == "part") return "parts";
  if (kind == "model") return "process_models";
  return nullptr;
}

}  // namespace

void Store::retire(const std::string& kind, const std::string& id, const std::string& author,
                   const std::string& reason) {
  const char* table = table_of(kind);
  if (table == nullptr) {
    throw StoreError(path_ + ": retire: unknown kind '" + kind +
                     "' (known: machine, tool, material, part, model)");
  }
  if (reason.empty()) throw StoreError(path_ + ": retire " + kind + " '" + id + "': give a reason");
  detail::Tx tx(db_.get(), path_);
  Stmt(db_.get(), path_,
       std::string("UPDATE ") + table +
           " SET retired_at_ms = ? WHERE id = ? AND retired_at_ms IS NULL")
      .bind(detail::now_ms(), id)
      .run();
  if (sqlite3_changes(db_.get()) == 0) {
    const bool exists =
        Stmt(db_.get(), path_, std::string("SELECT 1 FROM ") + table + " WHERE id = ?")
            .bind(id)
            .step();
    throw StoreError(path_ + ": retire: " + kind + " '" + id + "' " +
                     (exists ? "is retired already" : "is unknown"));
  }
  record_catalog_event(kind, id, "retired", author, reason, "");
  if (kind == "machine") {
    // Jobs planned for it are planned again (elsewhere, or refused when
    // they name it).
    for (const auto& j : jobs({.state = smc::config::JOB_PLANNED})) {
      if (j.planned_for == id || j.spec.machine_id() == id) {
        (void)transition(j.id, smc::config::JOB_PLANNED, smc::config::JOB_QUEUED,
                         "re-planned: machine " + id + " retired (" + reason + ")");
      }
    }
  }
  tx.commit();
}

}  // namespace smc::cell::store
