#include "smc/cell/planner.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "smc/cell/power_plan.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc/supervision/program.hpp"

namespace smc::cell {

namespace {

std::string describe(const store::ProcessModel& m) {
  std::ostringstream o;
  o << store::kind_name(m.kind) << " model " << m.id << " (" << store::provenance_name(m.provenance)
    << (m.validated ? ", validated" : ", not validated")
    << (m.part_id.empty() ? "" : ", part " + m.part_id) << ")";
  return o.str();
}

}  // namespace

Selection select_variant(const PlanInputs& in) {
  Selection sel;
  std::ostringstream why;
  why << "models for tool " << in.tool.id << " and material " << in.part.material_id << ": ";
  if (in.models.empty()) why << "none";
  for (size_t i = 0; i < in.models.size(); ++i) {
    const auto& m = in.models[i];
    why << (i ? "; " : "") << describe(m);
    if (!m.validated) continue;
    if (m.kind == store::ModelKind::kForceProcess && !sel.force) sel.force = m;
    if (m.kind == store::ModelKind::kMilling && !sel.milling) sel.milling = m;
  }
  why << ". ";
  if (sel.force && sel.milling) {
    sel.variant = smc::config::SMC_I;
    why << "SMC I (transfer line): a validated force-process model and a validated structural "
           "model exist, so the plan is made chatter-free by time-domain simulation and the "
           "force is held by the model-based controller.";
  } else {
    sel.variant = smc::config::SMC_II;
    why << "SMC II (job shop): ";
    if (!sel.force && !sel.milling)
      why << "no validated models";
    else if (!sel.force)
      why << "no validated force-process model";
    else
      why << "no validated structural model";
    why << ", so the job runs as programmed with chatter detection and suppression and the "
           "adaptive force controller.";
  }
  sel.explanation = why.str();
  return sel;
}

Planner::Planner(const std::string& grafcet_dir, smc::config::SupervisorConfig defaults)
    : smc1_text_(smc::documents::read_file(grafcet_dir + "/smc1.grafcet")),
      smc2_text_(smc::documents::read_file(grafcet_dir + "/smc2.grafcet")),
      defaults_(std::move(defaults)) {}

Plan Planner::plan(const PlanInputs& in, const Selection& sel) const {
  const auto t0 = std::chrono::steady_clock::now();
  Plan out;
  smc::config::SupervisorConfig& c = out.config;
  const smc::config::Job& job = in.job.spec;
  c = defaults_;
  c.set_variant(sel.variant);
  c.set_explanation(sel.explanation);
  auto* op = c.mutable_operation();
  op->set_teeth(in.tool.teeth);
  op->set_cutter_radius_mm(in.tool.radius_mm);
  const double rpm = job.spindle_rpm();
  if (!(rpm > 0)) throw std::runtime_error("job " + in.job.id + ": spindle_rpm must be > 0");
  op->set_slow_period_s(std::round(60.0 / rpm / op->sample_period_s()) * op->sample_period_s());
  // The geometry of the cut is known for every job; the process models only for SMC I.
  auto* mm = c.mutable_milling_model();
  mm->set_name(in.part.id);
  mm->mutable_cutter()->set_teeth(in.tool.teeth);
  mm->mutable_cutter()->set_radius_mm(in.tool.radius_mm);
  mm->mutable_cutter()->set_lead_angle_deg(in.tool.lead_angle_deg);
  mm->mutable_workpiece()->set_width_mm(in.part.width_mm);
  mm->mutable_workpiece()->set_offset_mm(in.part.offset_mm);
  mm->mutable_workpiece()->set_length_mm(in.part.length_mm);

  auto* prog = c.mutable_program();
  prog->set_part_id(in.part.id);
  prog->set_total_depth_mm(job.depth_mm());
  int passes = 1;
  if (sel.variant == smc::config::SMC_I) {
    c.set_grafcet_name("smc1.grafcet");
    c.set_grafcet_text(smc1_text_);
    for (const char* m : {"A", "B", "C", "I", "J", "L", "M"}) c.add_modules(m);
    *c.mutable_force_model() = sel.force->force;
    smc::config::MillingModel model = sel.milling->milling;
    *model.mutable_cutter() = mm->cutter();
    *model.mutable_workpiece() = mm->workpiece();
    *mm = model;
    const auto mach = smc::machining::from_proto(model, "milling_model");
    const double fpt = smc::supervision::feed_per_tooth_mm(job.feedrate_mm_s(),
                                                           static_cast<int>(in.tool.teeth), rpm);
    smc::machining::TdsSearchOptions so;
    so.initial_depth_mm = std::max(0.1, job.depth_mm() / 2);
    const auto crit = smc::machining::critical_depth_tds(mach, rpm, fpt, so);
    if (!crit.bounded && !(crit.stable_depth_mm > 0)) {
      throw std::runtime_error("job " + in.job.id + ": the cut chatters at every depth down to " +
                               std::to_string(so.min_depth_mm) + " mm at " + std::to_string(rpm) +
                               " rpm; choose another spindle speed");
    }
    // Unbounded and stable somewhere: stable up to the search's maximum depth.
    out.critical_depth_mm = crit.bounded ? crit.critical_depth_mm : so.max_depth_mm;
    const double allowed = margin * out.critical_depth_mm;
    passes = std::max(1, static_cast<int>(std::ceil(job.depth_mm() / allowed - 1e-9)));
    if (passes > smc::supervision::kMaxPasses) {
      throw std::runtime_error("job " + in.job.id + ": the critical depth " +
                               std::to_string(out.critical_depth_mm) + " mm would need " +
                               std::to_string(passes) + " passes (at most " +
                               std::to_string(smc::supervision::kMaxPasses) + ")");
    }
    std::ostringstream why;
    why << c.explanation() << " Critical depth at " << rpm << " rpm: " << out.critical_depth_mm
        << " mm; with a " << margin << " margin, " << passes << " equal pass"
        << (passes == 1 ? "" : "es") << " of " << job.depth_mm() / passes << " mm.";
    c.set_explanation(why.str());
  } else {
    c.set_grafcet_name("smc2.grafcet");
    c.set_grafcet_text(smc2_text_);
    for (const char* m : {"A", "B", "C", "D", "E", "F", "G", "H", "I", "J", "K", "M"}) {
      c.add_modules(m);
    }
  }
  for (int i = 0; i < passes; ++i) {
    auto* p = prog->add_passes();
    p->set_depth_mm(job.depth_mm() / passes);
    p->set_feedrate_mm_s(job.feedrate_mm_s());
    p->set_spindle_rpm(rpm);
  }
  out.planning_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

smc::config::SupervisorConfig Planner::for_machine(const smc::config::SupervisorConfig& plan,
                                                   const store::Machine& machine,
                                                   const std::string& config_id) {
  smc::config::SupervisorConfig c = plan;
  c.set_config_id(config_id);
  auto* m = c.mutable_machine();
  m->set_machine_id(machine.id);
  m->set_max_spindle_power_w(machine.max_spindle_power_w);
  m->set_max_feedrate_mm_s(machine.max_feedrate_mm_s);
  m->set_max_spindle_rpm(machine.max_spindle_rpm);
  // SMC I: each pass's F_ref from the models, for this machine's power.
  plan_force_references(c);
  return c;
}

}  // namespace smc::cell
