// Demo seed data. The paper's numbers (shared/DOMAIN.md) are data: the model
// documents come from cell/models/ when present, and only fall back to the
// values written out here (the appendix and eq. 1) when they are not.

#include "smc/cell/store/seed.hpp"

#include <array>
#include <filesystem>

#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"

namespace smc::cell::store {

namespace {

constexpr const char* kTool = "fm-r25-4t";
constexpr const char* kMaterial = "6061-T6";
constexpr std::array<const char*, 2> kMills{"mill-1", "mill-2"};

// Lead angle when no cell/models/paper_face_mill.textproto says otherwise:
// the paper's Figure 2 is missing; the lead angle matters little (DOMAIN.md
// item 4), but it must be above 0 for the thrust to have the axial component
// the chatter detector reads (F_z).
constexpr double kBuiltinLeadAngleDeg = 15;

void set_pressure(smc::config::PowerLawPressure* p, double c, double fe, double de, double se) {
  p->set_coefficient_kn_per_mm2(c);
  p->set_feed_exponent(fe);
  p->set_depth_exponent(de);
  p->set_speed_exponent(se);
}

void add_mode(google::protobuf::RepeatedPtrField<smc::config::Mode>* modes, double w, double z,
              double k_n_per_mm) {
  auto* m = modes->Add();
  m->set_natural_frequency_rad_s(w);
  m->set_damping_ratio(z);
  m->set_stiffness_n_per_mm(k_n_per_mm);
}

// The paper's appendix: pressures A1-A2, structure A6-A9, the reference cut
// of section III; geometry: the part centred under the cutter and nearly as
// wide as it (DOMAIN.md item 4), where one 2 mm pass chatters. The same
// values as cell/models/paper_face_mill.textproto (a test keeps them equal).
smc::config::MillingModel builtin_milling_model() {
  smc::config::MillingModel m;
  m.set_name("paper_face_mill");
  m.mutable_cutter()->set_teeth(4);
  m.mutable_cutter()->set_radius_mm(25);
  m.mutable_cutter()->set_lead_angle_deg(kBuiltinLeadAngleDeg);
  m.mutable_workpiece()->set_width_mm(48);
  m.mutable_workpiece()->set_offset_mm(0);
  m.mutable_workpiece()->set_length_mm(150);
  auto* law = m.mutable_law()->mutable_power_law();
  set_pressure(law->mutable_cutting(), 0.29, -0.25, -0.13, -0.72);
  set_pressure(law->mutable_thrust(), 0.16, -0.40, -0.41, -0.58);
  auto* s = m.mutable_structure();
  add_mode(s->mutable_tool_x(), 4500, 0.07, 14000);
  add_mode(s->mutable_tool_y(), 4100, 0.11, 14000);
  add_mode(s->mutable_part_x(), 2600, 0.09, 9500);
  add_mode(s->mutable_part_y(), 2100, 0.22, 9500);
  m.set_delay(smc::config::DELAY_TOOTH_PERIOD);
  m.set_internal_step_s(1e-5);
  m.set_provenance(smc::config::PROVENANCE_HANDBOOK);  // the paper's published values
  auto* cut = m.mutable_reference_cut();
  cut->set_depth_mm(2);
  cut->set_feedrate_mm_s(10);
  cut->set_spindle_rpm(1500);
  return m;
}

// Eq. (1): F_Y = 0.76 d^0.65 f^0.63 (kN, mm, mm/tooth).
smc::config::ForceProcessModel builtin_force_model() {
  smc::config::ForceProcessModel f;
  f.set_k_kn(0.76);
  f.set_beta(0.65);
  f.set_alpha(0.63);
  f.set_provenance(smc::config::PROVENANCE_IDENTIFIED);  // by the paper's experiments
  return f;
}

// Loads `dir/name` into `msg` when the file exists; returns where it came from.
std::string load_or_builtin(const std::string& dir, const char* name,
                            google::protobuf::Message& msg) {
  if (!dir.empty()) {
    const auto path = (std::filesystem::path(dir) / name).lexically_normal();
    if (std::filesystem::exists(path)) {
      msg.Clear();
      smc::documents::load(path.string(), msg);  // DocumentError: file:line:col
      return "from " + path.filename().string();
    }
  }
  return "built-in paper values (no " + std::string(name) + ")";
}

smc::config::Provenance provenance_or(smc::config::Provenance p, smc::config::Provenance dflt) {
  return p == smc::config::PROVENANCE_UNSPECIFIED ? dflt : p;
}

}  // namespace

std::string default_models_dir() { return SMC_CELL_MODELS_DIR; }

std::int64_t seed_demo(Store& store, const SeedOptions& options) {
  // Documents first: a malformed one stops the seed before anything is written.
  smc::config::MillingModel milling = builtin_milling_model();
  const std::string milling_src =
      load_or_builtin(options.models_dir, "paper_face_mill.textproto", milling);
  smc::config::ForceProcessModel force = builtin_force_model();
  const std::string force_src =
      load_or_builtin(options.models_dir, "paper_force_model.textproto", force);

  std::int64_t inserted = 0;
  store.transaction([&] {
    for (const char* id : kMills) {
      if (store.machine(id)) continue;
      store.put_machine(
          Machine{id, std::string("face mill ") + id + " (the paper's machine)", 745.7, 36, 3000});
      ++inserted;
    }
    if (!store.tool(kTool)) {
      const auto& c = milling.cutter();
      store.put_tool(Tool{kTool, "face mill R25, 4 carbide teeth", c.teeth() > 0 ? c.teeth() : 4,
                          c.radius_mm() > 0 ? c.radius_mm() : 25, c.lead_angle_deg()});
      ++inserted;
    }
    if (!store.material(kMaterial)) {
      store.put_material(Material{kMaterial, "6061-T6 aluminium"});
      ++inserted;
    }
    // Both parts have the paper's geometry and cut, so that the job-shop
    // part's single 2 mm pass chatters under SMC II as in the paper's
    // experiment; the transfer-line part's models plan it chatter-free.
    const auto& wp = milling.workpiece();
    const double width = wp.width_mm() > 0 ? wp.width_mm() : 48;
    const double length = wp.length_mm() > 0 ? wp.length_mm() : 150;
    const auto& cut = milling.reference_cut();
    const double depth = cut.depth_mm() > 0 ? cut.depth_mm() : 2;
    const double feed = cut.feedrate_mm_s() > 0 ? cut.feedrate_mm_s() : 10;
    const double rpm = cut.spindle_rpm() > 0 ? cut.spindle_rpm() : 1500;
    if (!store.part("bracket-tl")) {
      store.put_part(Part{"bracket-tl", "bracket (transfer line: validated models, SMC I)",
                          kMaterial, kTool, width, wp.offset_mm(), length, depth, feed, rpm});
      ++inserted;
    }
    if (!store.part("housing-js")) {
      store.put_part(Part{"housing-js", "housing (job shop: no models, SMC II)", kMaterial, kTool,
                          width, wp.offset_mm(), 120, depth, feed, rpm});
      ++inserted;
    }
    for (const char* mill : kMills) {
      const std::string base = std::string("bracket-tl.") + mill;
      if (!store.model(base + ".force")) {
        ProcessModel m;
        m.id = base + ".force";
        m.kind = ModelKind::kForceProcess;
        m.machine_id = mill;
        m.tool_id = kTool;
        m.material_id = kMaterial;
        m.part_id = "bracket-tl";
        m.provenance = provenance_or(force.provenance(), smc::config::PROVENANCE_IDENTIFIED);
        m.validated = true;
        m.force = force;
        m.note = "eq. (1) of the paper; " + force_src;
        store.add_model(m);
        ++inserted;
      }
      if (!store.model(base + ".milling")) {
        ProcessModel m;
        m.id = base + ".milling";
        m.kind = ModelKind::kMilling;
        m.machine_id = mill;
        m.tool_id = kTool;
        m.material_id = kMaterial;
        m.part_id = "bracket-tl";
        m.provenance = provenance_or(milling.provenance(), smc::config::PROVENANCE_HANDBOOK);
        m.validated = true;  // for this part: its 1 mm passes were run without chatter
        m.milling = milling;
        m.note = "appendix structure and cutting law (paper); " + milling_src;
        store.add_model(m);
        ++inserted;
      }
    }
  });
  return inserted;
}

}  // namespace smc::cell::store
