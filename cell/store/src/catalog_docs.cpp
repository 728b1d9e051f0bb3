#include "smc/cell/store/catalog_docs.hpp"

#include <google/protobuf/util/message_differencer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <type_traits>

#include "smc/documents/load.hpp"
#include "smc/machining/model_proto.hpp"

namespace smc::cell::store {

namespace fs = std::filesystem;
namespace cfg = smc::config;

namespace {

bool document_file(const fs::path& p) {
  const auto e = p.extension().string();
  return e == ".textproto" || e == ".txtpb" || e == ".pbtxt" || e == ".json";
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool valid_id(const std::string& id, std::size_t max_len) {
  if (id.empty() || id.size() > max_len) return false;
  for (std::size_t i = 0; i < id.size(); ++i) {
    const char c = id[i];
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!alnum && (i == 0 || (c != '-' && c != '_' && c != '.'))) return false;
  }
  return true;
}

// ---- database rows as documents, and documents with their defaults

cfg::CatalogMachine to_doc(const Machine& m) {
  cfg::CatalogMachine d;
  d.set_id(m.id);
  d.set_name(m.name);
  d.set_max_spindle_power_w(m.max_spindle_power_w);
  d.set_max_feedrate_mm_s(m.max_feedrate_mm_s);
  d.set_min_spindle_rpm(m.min_spindle_rpm);
  d.set_max_spindle_rpm(m.max_spindle_rpm);
  d.set_drive(m.drive.empty() ? "simulated" : m.drive);
  if (!m.wideband.is_default()) {
    auto* w = d.mutable_wideband();
    w->set_samples_per_tick(m.wideband.samples_per_tick);
    w->set_cutoff_hz(m.wideband.cutoff_hz);
    w->set_filter_order(m.wideband.filter_order);
    w->set_noise_rms_n(m.wideband.noise_rms_n);
  }
  return d;
}
cfg::CatalogMachine normal(cfg::CatalogMachine d) {
  if (d.name().empty()) d.set_name(d.id());
  if (d.drive().empty()) d.set_drive("simulated");
  // A channel given without its order has the edge's default, 2; one with
  // nothing in it is the cell's default channel.
  if (d.has_wideband() && d.wideband().samples_per_tick() != 0 &&
      d.wideband().filter_order() == 0) {
    d.mutable_wideband()->set_filter_order(2);
  }
  if (d.has_wideband() && d.wideband().ByteSizeLong() == 0) d.clear_wideband();
  return d;
}
Machine to_row(const cfg::CatalogMachine& d) {
  const auto& w = d.wideband();
  return Machine{
      d.id(),
      d.name(),
      d.max_spindle_power_w(),
      d.max_feedrate_mm_s(),
      d.max_spindle_rpm(),
      d.min_spindle_rpm(),
      d.drive(),
      0,
      WidebandChannel{w.samples_per_tick(), w.cutoff_hz(), w.filter_order(), w.noise_rms_n()}};
}

cfg::CatalogTool to_doc(const Tool& t) {
  cfg::CatalogTool d;
  d.set_id(t.id);
  d.set_name(t.name);
  d.set_teeth(t.teeth);
  d.set_radius_mm(t.radius_mm);
  d.set_lead_angle_deg(t.lead_angle_deg);
  return d;
}
cfg::CatalogTool normal(cfg::CatalogTool d) {
  if (d.name().empty()) d.set_name(d.id());
  return d;
}
Tool to_row(const cfg::CatalogTool& d) {
  return Tool{d.id(), d.name(), d.teeth(), d.radius_mm(), d.lead_angle_deg(), 0};
}

cfg::CatalogMaterial to_doc(const Material& m) {
  cfg::CatalogMaterial d;
  d.set_id(m.id);
  d.set_name(m.name);
  return d;
}
cfg::CatalogMaterial normal(cfg::CatalogMaterial d) {
  if (d.name().empty()) d.set_name(d.id());
  return d;
}
Material to_row(const cfg::CatalogMaterial& d) { return Material{d.id(), d.name(), 0}; }

cfg::CatalogPart to_doc(const Part& p) {
  cfg::CatalogPart d;
  d.set_id(p.id);
  d.set_name(p.name);
  d.set_material_id(p.material_id);
  d.set_tool_id(p.tool_id);
  d.set_width_mm(p.width_mm);
  d.set_offset_mm(p.offset_mm);
  d.set_length_mm(p.length_mm);
  d.set_total_depth_mm(p.total_depth_mm);
  d.set_feedrate_mm_s(p.feedrate_mm_s);
  d.set_spindle_rpm(p.spindle_rpm);
  d.set_speed_change_allowed(p.speed_change_allowed);
  return d;
}
cfg::CatalogPart normal(cfg::CatalogPart d) {
  if (d.name().empty()) d.set_name(d.id());
  return d;
}
Part to_row(const cfg::CatalogPart& d) {
  return Part{d.id(),
              d.name(),
              d.material_id(),
              d.tool_id(),
              d.width_mm(),
              d.offset_mm(),
              d.length_mm(),
              d.total_depth_mm(),
              d.feedrate_mm_s(),
              d.spindle_rpm(),
              0,
              d.speed_change_allowed()};
}

cfg::CatalogModel to_doc(const ProcessModel& m) {
  cfg::CatalogModel d;
  d.set_id(m.id);
  d.set_machine_id(m.machine_id);
  d.set_tool_id(m.tool_id);
  d.set_material_id(m.material_id);
  d.set_part_id(m.part_id);
  if (m.kind == ModelKind::kForceProcess) {
    *d.mutable_force_process() = m.force;
  } else {
    *d.mutable_milling() = m.milling;
  }
  d.set_provenance(m.provenance);
  d.set_validated(m.validated);
  d.set_note(m.note);
  if (m.validity.ByteSizeLong() > 0) *d.mutable_validity() = m.validity;
  return d;
}
// Provenance and validation live at the top; the inner document's copies
// (which the database keeps equal) are folded in and cleared.
cfg::CatalogModel normal(cfg::CatalogModel d) {
  if (d.has_force_process()) {
    auto* f = d.mutable_force_process();
    if (d.provenance() == cfg::PROVENANCE_UNSPECIFIED) d.set_provenance(f->provenance());
    d.set_validated(d.validated() || f->validated());
    f->clear_provenance();
    f->clear_validated();
  } else if (d.has_milling()) {
    auto* m = d.mutable_milling();
    if (d.provenance() == cfg::PROVENANCE_UNSPECIFIED) d.set_provenance(m->provenance());
    d.set_validated(d.validated() || m->validated());
    m->clear_provenance();
    m->clear_validated();
  }
  return d;
}
ProcessModel to_row(const cfg::CatalogModel& d) {
  ProcessModel m;
  m.id = d.id();
  m.kind = d.has_force_process() ? ModelKind::kForceProcess : ModelKind::kMilling;
  m.machine_id = d.machine_id();
  m.tool_id = d.tool_id();
  m.material_id = d.material_id();
  m.part_id = d.part_id();
  m.provenance = d.provenance();
  m.validated = d.validated();
  if (d.has_force_process()) {
    m.force = d.force_process();
    if (m.force.has_fit()) m.fit = m.force.fit();
  }
  if (d.has_milling()) m.milling = d.milling();
  m.note = d.note();
  m.validity = d.validity();
  return m;
}

// "what changed" between two documents of one entity, or "" when equal.
std::string difference(const google::protobuf::Message& before,
                       const google::protobuf::Message& after) {
  google::protobuf::util::MessageDifferencer diff;
  std::string report;
  diff.ReportDifferencesToString(&report);
  if (diff.Compare(before, after)) return {};
  for (auto& c : report) {
    if (c == '\n') c = ';';
  }
  while (!report.empty() && (report.back() == ';' || report.back() == ' ')) report.pop_back();
  return report.empty() ? "changed" : report;
}

template <class T>
void add_all(std::vector<FromFile<T>>& out, const std::string& file,
             const google::protobuf::RepeatedPtrField<T>& docs) {
  int i = 0;
  for (const auto& d : docs) out.push_back({file, i++, d});
}

// A machine's wideband channel: what the edge and its drives take. The edge
// samples every 0.5 ms, so a channel of n samples a period runs at n x 2 kHz.
void check_wideband(common::Diagnostics& problems, const std::string& where,
                    const cfg::WidebandChannel& c, const std::string& drive) {
  const auto n = c.samples_per_tick();
  if (n == 0) {
    problems.add(where + ".samples_per_tick", "is 0 but the channel's other fields are given",
                 "give its samples per 0.5 ms period (1: 2 kHz ... 5: 10 kHz), or leave the "
                 "whole wideband channel out for the cell's default");
    return;
  }
  if (n > 5) {
    problems.add(where + ".samples_per_tick", "must be 1-5, got " + std::to_string(n),
                 "give the channel's samples per 0.5 ms period (the drives bring at most 5: "
                 "10 kHz)");
    return;
  }
  if (drive == "simulated" && 50 % n != 0) {
    problems.add(where + ".samples_per_tick",
                 std::to_string(n) + " does not divide the simulated mill's 50 steps a period",
                 "use 1 (2 kHz), 2 (4 kHz) or 5 (10 kHz)");
  }
  const double nyquist = n * 1000.0;
  if (!(std::isfinite(c.cutoff_hz()) && c.cutoff_hz() > 0 && c.cutoff_hz() < nyquist)) {
    problems.add(
        where + ".cutoff_hz",
        "must be > 0 and below the channel's Nyquist frequency (" + num(nyquist) + " Hz), got " +
            num(c.cutoff_hz()),
        "give the anti-alias filter's cut-off (E was measured through 350-700 Hz at 2 kHz, "
        "1000-1400 Hz at 4 kHz, 3500 Hz at 10 kHz; edge/CHATTER.md, \"What the "
        "channel's filter costs E\")");
  }
  if (c.filter_order() % 2 != 0 || c.filter_order() > 8) {
    problems.add(where + ".filter_order",
                 "must be even, 2-8, got " + std::to_string(c.filter_order()),
                 "give the anti-alias filter's Butterworth order (E was measured through 2-8 at "
                 "2 and 4 kHz, 8 at 10 kHz)");
  }
  if (!(std::isfinite(c.noise_rms_n()) && c.noise_rms_n() >= 0 && c.noise_rms_n() <= 1000)) {
    problems.add(where + ".noise_rms_n", "must be 0-1000 N rms, got " + num(c.noise_rms_n()),
                 "give the channel's noise, e.g. 2, or 0 for none taken out");
  }
}

void read_one(const fs::path& path, CatalogDocuments& out, common::Diagnostics& problems) {
  cfg::Catalog c;
  try {
    smc::documents::load(path.string(), c);
  } catch (const smc::documents::DocumentError& e) {
    problems.append(e.diagnostics());
    return;
  }
  const fs::path dir = path.parent_path();
  int i = 0;
  for (auto& m : *c.mutable_models()) {
    const std::string where =
        path.string() + ": models[" + std::to_string(i++) + "] '" + m.id() + "'";
    try {
      if (!m.milling_file().empty()) {
        const auto f = (dir / m.milling_file()).lexically_normal().string();
        smc::documents::load(f, *m.mutable_milling());
        m.clear_milling_file();
      }
      if (!m.force_process_file().empty()) {
        const auto f = (dir / m.force_process_file()).lexically_normal().string();
        smc::documents::load(f, *m.mutable_force_process());
        m.clear_force_process_file();
      }
    } catch (const smc::documents::DocumentError& e) {
      problems.add(where, "its model file cannot be read: " + std::string(e.what()),
                   "fix the file, or the path (relative to " + path.string() + ")");
    }
  }
  const std::string file = path.string();
  add_all(out.machines, file, c.machines());
  add_all(out.tools, file, c.tools());
  add_all(out.materials, file, c.materials());
  add_all(out.parts, file, c.parts());
  add_all(out.models, file, c.models());
}

template <class T>
std::string at(const FromFile<T>& f, const char* kind) {
  return f.file + ": " + kind + "[" + std::to_string(f.index) + "] '" + f.doc.id() + "'";
}

}  // namespace

Machine machine_from_doc(const cfg::CatalogMachine& doc) { return to_row(normal(doc)); }

std::string default_catalog_dir() {
  return fs::path(SMC_CELL_CATALOG_DIR).lexically_normal().string();
}

CatalogDocuments load_catalog(const std::vector<std::string>& paths) {
  CatalogDocuments out;
  common::Diagnostics problems;
  if (paths.empty()) problems.add("", "no catalog files or folders given", "name one or more");
  for (const auto& p : paths) {
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(p, ec)) {
        if (e.is_regular_file() && document_file(e.path())) files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      if (files.empty()) {
        problems.add(p, "holds no catalog documents (.textproto, .txtpb, .pbtxt, .json)",
                     "name a folder of smc.config.Catalog documents");
      }
      for (const auto& f : files) read_one(f, out, problems);
    } else if (fs::exists(p, ec)) {
      read_one(p, out, problems);
    } else {
      problems.add(p, "no such file or folder", "check the path");
    }
  }
  if (!problems.ok()) throw CatalogError(std::move(problems));
  return out;
}

std::vector<CatalogChange> apply_catalog(Store& store, const CatalogDocuments& docs,
                                         const ApplyOptions& options) {
  common::Diagnostics problems;
  std::vector<CatalogChange> changes;
  // Ids in use after the apply: the database's (not retired) and the documents'.
  std::set<std::string> machines, tools, materials;
  std::map<std::string, std::string> part_material;
  for (const auto& m : store.machines()) {
    if (m.retired_at_ms == 0) machines.insert(m.id);
  }
  for (const auto& t : store.tools()) {
    if (t.retired_at_ms == 0) tools.insert(t.id);
  }
  for (const auto& m : store.materials()) {
    if (m.retired_at_ms == 0) materials.insert(m.id);
  }
  for (const auto& p : store.parts()) {
    if (p.retired_at_ms == 0) part_material[p.id] = p.material_id;
  }
  for (const auto& f : docs.machines) machines.insert(f.doc.id());
  for (const auto& f : docs.tools) tools.insert(f.doc.id());
  for (const auto& f : docs.materials) materials.insert(f.doc.id());
  for (const auto& f : docs.parts) part_material[f.doc.id()] = f.doc.material_id();
  const auto list = [](const auto& ids) {
    std::string s;
    for (const auto& id : ids) {
      if constexpr (std::is_same_v<std::decay_t<decltype(id)>, std::string>) {
        s += (s.empty() ? "" : ", ") + id;
      } else {
        s += (s.empty() ? "" : ", ") + id.first;
      }
    }
    return s.empty() ? std::string("none") : s;
  };
  // Duplicates within the documents.
  const auto duplicates = [&](const auto& items, const char* kind) {
    std::map<std::string, std::string> first;
    for (const auto& f : items) {
      const auto [it, fresh] = first.emplace(f.doc.id(), at(f, kind));
      if (!fresh && !f.doc.id().empty()) {
        problems.add(at(f, kind), "the id is given twice (first at " + it->second + ")",
                     "give each entity of a kind its own id");
      }
    }
  };
  duplicates(docs.machines, "machines");
  duplicates(docs.tools, "tools");
  duplicates(docs.materials, "materials");
  duplicates(docs.parts, "parts");
  duplicates(docs.models, "models");
  const auto check_id = [&](const std::string& where, const std::string& id, std::size_t max_len,
                            std::int64_t retired_at) {
    if (!valid_id(id, max_len)) {
      problems.add(where + ".id", id.empty() ? "missing" : "'" + id + "' is not a valid id",
                   "use 1 to " + std::to_string(max_len) +
                       " letters, digits, '-', '_' or '.', starting with a letter or digit");
      return false;
    }
    if (retired_at != 0) {
      problems.add(where + ".id", "'" + id + "' is retired; ids are never reused",
                   "choose another id");
      return false;
    }
    return true;
  };
  const auto positive = [&](const std::string& where, const char* field, double v,
                            const char* unit) {
    if (!(std::isfinite(v) && v > 0)) {
      problems.add(where + "." + field, "must be > 0, got " + num(v),
                   std::string("give it in ") + unit);
    }
  };

  for (const auto& f : docs.machines) {
    const std::string w = at(f, "machines");
    const auto row = store.machine(f.doc.id());
    if (!check_id(w, f.doc.id(), 31, row ? row->retired_at_ms : 0)) continue;
    const auto d = normal(f.doc);
    positive(w, "max_spindle_power_w", d.max_spindle_power_w(), "W, e.g. 745.7");
    positive(w, "max_feedrate_mm_s", d.max_feedrate_mm_s(), "mm/s, e.g. 36");
    positive(w, "max_spindle_rpm", d.max_spindle_rpm(), "rev/min, e.g. 3000");
    if (!(std::isfinite(d.min_spindle_rpm()) && d.min_spindle_rpm() >= 0 &&
          d.min_spindle_rpm() < d.max_spindle_rpm())) {
      problems.add(w + ".min_spindle_rpm",
                   "must be >= 0 and below max_spindle_rpm (" + num(d.max_spindle_rpm()) +
                       "), got " + num(d.min_spindle_rpm()),
                   "give the lowest speed the spindle runs at, or 0");
    }
    if (d.drive() != "simulated" && d.drive() != "linuxcnc") {
      problems.add(w + ".drive", "unknown drive '" + d.drive() + "'",
                   "use \"simulated\" or \"linuxcnc\"");
    }
    if (d.has_wideband()) check_wideband(problems, w + ".wideband", d.wideband(), d.drive());
    const std::string diff = row ? difference(to_doc(*row), d) : "";
    changes.push_back({"machine", d.id(),
                       !row           ? "created"
                       : diff.empty() ? "unchanged"
                                      : "updated",
                       diff});
  }
  for (const auto& f : docs.tools) {
    const std::string w = at(f, "tools");
    const auto row = store.tool(f.doc.id());
    if (!check_id(w, f.doc.id(), 63, row ? row->retired_at_ms : 0)) continue;
    const auto d = normal(f.doc);
    if (d.teeth() < 1 || d.teeth() > 1000) {
      problems.add(w + ".teeth", "must be 1 to 1000, got " + std::to_string(d.teeth()),
                   "give the cutter's number of teeth");
    }
    positive(w, "radius_mm", d.radius_mm(), "mm");
    if (!(std::isfinite(d.lead_angle_deg()) && d.lead_angle_deg() >= 0 &&
          d.lead_angle_deg() < 90)) {
      problems.add(w + ".lead_angle_deg", "must be in [0, 90), got " + num(d.lead_angle_deg()),
                   "give the lead angle in degrees (0: square shoulder)");
    }
    const std::string diff = row ? difference(to_doc(*row), d) : "";
    changes.push_back({"tool", d.id(),
                       !row           ? "created"
                       : diff.empty() ? "unchanged"
                                      : "updated",
                       diff});
  }
  for (const auto& f : docs.materials) {
    const std::string w = at(f, "materials");
    const auto row = store.material(f.doc.id());
    if (!check_id(w, f.doc.id(), 63, row ? row->retired_at_ms : 0)) continue;
    const auto d = normal(f.doc);
    const std::string diff = row ? difference(to_doc(*row), d) : "";
    changes.push_back({"material", d.id(),
                       !row           ? "created"
                       : diff.empty() ? "unchanged"
                                      : "updated",
                       diff});
  }
  for (const auto& f : docs.parts) {
    const std::string w = at(f, "parts");
    const auto row = store.part(f.doc.id());
    if (!check_id(w, f.doc.id(), 63, row ? row->retired_at_ms : 0)) continue;
    const auto d = normal(f.doc);
    if (!materials.count(d.material_id())) {
      problems.add(
          w + ".material_id",
          d.material_id().empty() ? "missing" : "unknown material '" + d.material_id() + "'",
          "use one of: " + list(materials));
    }
    if (!d.tool_id().empty() && !tools.count(d.tool_id())) {
      problems.add(w + ".tool_id", "unknown tool '" + d.tool_id() + "'",
                   "use one of: " + list(tools) + ", or leave it out");
    }
    positive(w, "width_mm", d.width_mm(), "mm, across the feed");
    positive(w, "length_mm", d.length_mm(), "mm, along the feed");
    if (!std::isfinite(d.offset_mm())) {
      problems.add(w + ".offset_mm", "must be finite", "give it in mm (0: centred)");
    }
    positive(w, "total_depth_mm", d.total_depth_mm(), "mm");
    positive(w, "feedrate_mm_s", d.feedrate_mm_s(), "mm/s");
    positive(w, "spindle_rpm", d.spindle_rpm(), "rev/min");
    const std::string diff = row ? difference(to_doc(*row), d) : "";
    changes.push_back({"part", d.id(),
                       !row           ? "created"
                       : diff.empty() ? "unchanged"
                                      : "updated",
                       diff});
  }
  for (const auto& f : docs.models) {
    const std::string w = at(f, "models");
    const auto row = store.model(f.doc.id());
    if (!check_id(w, f.doc.id(), 63, row ? row->retired_at_ms : 0)) continue;
    const auto d = normal(f.doc);
    if (!d.has_force_process() && !d.has_milling()) {
      problems.add(w, "has no model document",
                   "give force_process { ... } or milling { ... } (or force_process_file / "
                   "milling_file)");
      continue;
    }
    if (!machines.count(d.machine_id())) {
      problems.add(w + ".machine_id",
                   d.machine_id().empty() ? "missing" : "unknown machine '" + d.machine_id() + "'",
                   "use one of: " + list(machines) + " (structural models are per machine)");
    }
    if (!tools.count(d.tool_id())) {
      problems.add(w + ".tool_id",
                   d.tool_id().empty() ? "missing" : "unknown tool '" + d.tool_id() + "'",
                   "use one of: " + list(tools));
    }
    if (!materials.count(d.material_id())) {
      problems.add(
          w + ".material_id",
          d.material_id().empty() ? "missing" : "unknown material '" + d.material_id() + "'",
          "use one of: " + list(materials));
    }
    if (!d.part_id().empty()) {
      const auto p = part_material.find(d.part_id());
      if (p == part_material.end()) {
        problems.add(w + ".part_id", "unknown part '" + d.part_id() + "'",
                     "use one of: " + list(part_material) + ", or leave it out for any part");
      } else if (p->second != d.material_id()) {
        problems.add(w + ".part_id",
                     "part '" + d.part_id() + "' is made of '" + p->second + "', not '" +
                         d.material_id() + "'",
                     "set material_id to '" + p->second + "'");
      }
    }
    if (d.has_force_process()) {
      const auto& fm = d.force_process();
      if (!(std::isfinite(fm.k_kn()) && fm.k_kn() > 0 && std::isfinite(fm.alpha()) &&
            fm.alpha() > 0 && std::isfinite(fm.beta()) && fm.beta() > 0)) {
        problems.add(w + ".force_process", "k_kn, alpha and beta must be > 0",
                     "give F_Y = K d^beta f^alpha with K in kN, e.g. k_kn: 0.76 beta: 0.65 "
                     "alpha: 0.63");
      }
    } else {
      try {
        (void)smc::machining::from_proto(d.milling(), w + ".milling");
      } catch (const std::exception& e) {
        problems.add(w + ".milling", e.what(), "fix the milling model's fields");
      }
    }
    const auto& v = d.validity();
    for (const double x : {v.min_spindle_rpm(), v.max_spindle_rpm(), v.max_depth_mm(),
                           v.min_width_mm(), v.max_width_mm()}) {
      if (!(std::isfinite(x) && x >= 0)) {
        problems.add(w + ".validity", "bounds must be >= 0 (0: no bound)", "fix the bound");
        break;
      }
    }
    if (row) {
      const std::string diff = difference(normal(to_doc(*row)), d);
      if (!diff.empty()) {
        problems.add(w, "model '" + d.id() + "' exists with another document (" + diff + ")",
                     "models are never replaced: give the new one its own id and retire '" +
                         d.id() + "' (smc-cell catalog retire model " + d.id() +
                         "); validate or suspect a model with smc-cell model validate|suspect");
      }
      changes.push_back({"model", d.id(), "unchanged", ""});
    } else {
      changes.push_back({"model", d.id(), "created", ""});
    }
  }
  if (!problems.ok()) throw CatalogError(std::move(problems));
  if (options.dry_run) return changes;

  store.transaction([&] {
    const auto record = [&](const CatalogChange& c) {
      if (c.action != "unchanged") {
        store.record_catalog_event(c.kind, c.id, c.action, options.author, options.reason,
                                   c.detail);
      }
    };
    std::size_t k = 0;
    for (const auto& f : docs.machines) {
      const auto& c = changes[k++];
      if (c.action != "unchanged") store.put_machine(to_row(normal(f.doc)));
      record(c);
    }
    for (const auto& f : docs.tools) {
      const auto& c = changes[k++];
      if (c.action != "unchanged") store.put_tool(to_row(normal(f.doc)));
      record(c);
    }
    for (const auto& f : docs.materials) {
      const auto& c = changes[k++];
      if (c.action != "unchanged") store.put_material(to_row(normal(f.doc)));
      record(c);
    }
    for (const auto& f : docs.parts) {
      const auto& c = changes[k++];
      if (c.action != "unchanged") store.put_part(to_row(normal(f.doc)));
      record(c);
    }
    for (const auto& f : docs.models) {
      const auto& c = changes[k++];
      if (c.action != "unchanged") (void)store.add_model(to_row(normal(f.doc)));
      record(c);
    }
    // A machine whose limits changed: the jobs planned for it (or for any
    // machine) are planned again, against the new limits.
    std::set<std::string> changed;
    for (const auto& c : changes) {
      if (c.kind == "machine" && c.action == "updated") changed.insert(c.id);
    }
    if (changed.empty()) return;
    for (const auto& j : store.jobs({.state = cfg::JOB_PLANNED})) {
      const std::string& on = !j.spec.machine_id().empty() ? j.spec.machine_id() : j.planned_for;
      std::string which;
      for (const auto& m : changed) {
        if (on.empty() || on == m) which += (which.empty() ? "" : ", ") + m;
      }
      if (which.empty()) continue;
      (void)store.transition(j.id, cfg::JOB_PLANNED, cfg::JOB_QUEUED,
                             "re-planned: machine " + which + " changed (" + options.reason + ")");
    }
  });
  return changes;
}

cfg::Catalog export_catalog(Store& store) {
  cfg::Catalog c;
  for (const auto& m : store.machines()) {
    if (m.retired_at_ms == 0) *c.add_machines() = to_doc(m);
  }
  for (const auto& t : store.tools()) {
    if (t.retired_at_ms == 0) *c.add_tools() = to_doc(t);
  }
  for (const auto& m : store.materials()) {
    if (m.retired_at_ms == 0) *c.add_materials() = to_doc(m);
  }
  for (const auto& p : store.parts()) {
    if (p.retired_at_ms == 0) *c.add_parts() = to_doc(p);
  }
  for (const auto& m : store.find_models("", "", "", "")) *c.add_models() = normal(to_doc(m));
  std::sort(c.mutable_models()->begin(), c.mutable_models()->end(),
            [](const auto& a, const auto& b) { return a.id() < b.id(); });
  return c;
}

std::vector<std::string> write_catalog(const cfg::Catalog& catalog, const std::string& dir) {
  fs::create_directories(dir);
  std::vector<std::string> files;
  const auto write = [&](const char* name, const cfg::Catalog& part, int count) {
    if (count == 0) return;
    const auto path = (fs::path(dir) / name).string();
    std::ofstream out(path);
    out << "# proto-file: idl/smc_config.proto\n# proto-message: smc.config.Catalog\n"
        << "# Written by smc-cell catalog export; apply with smc-cell catalog apply.\n"
        << smc::documents::to_textproto(part);
    if (!out) throw CatalogError(common::Diagnostic{path, "cannot be written", "check the folder"});
    files.push_back(path);
  };
  cfg::Catalog part;
  *part.mutable_machines() = catalog.machines();
  write("machines.textproto", part, catalog.machines_size());
  part.Clear();
  *part.mutable_tools() = catalog.tools();
  write("tools.textproto", part, catalog.tools_size());
  part.Clear();
  *part.mutable_materials() = catalog.materials();
  write("materials.textproto", part, catalog.materials_size());
  part.Clear();
  *part.mutable_parts() = catalog.parts();
  write("parts.textproto", part, catalog.parts_size());
  part.Clear();
  *part.mutable_models() = catalog.models();
  write("models.textproto", part, catalog.models_size());
  return files;
}

}  // namespace smc::cell::store
