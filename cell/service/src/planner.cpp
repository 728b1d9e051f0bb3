#include "smc/cell/planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "smc/cell/power_plan.hpp"
#include "smc/documents/load.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc/supervision/gcode.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc/supervision/program.hpp"

namespace smc::cell {

namespace {

std::string fmt(double v, int digits = 3) {
  std::ostringstream o;
  o.precision(digits);
  o << v;
  return o.str();
}

// A limit or a job's value as written: 2000, 0.5, 47.5.
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// The job's conditions a model's validity range is checked against.
struct Cut {
  double rpm = 0, width_mm = 0;
};

Cut cut_of(const PlanInputs& in) { return {in.job.spec.spindle_rpm(), in.part.width_mm}; }

// Why the job is outside the model's validity range, or "" (0: no bound).
std::string out_of_range(const store::ProcessModel& m, const Cut& c) {
  const auto& v = m.validity;
  if (v.min_spindle_rpm() > 0 && c.rpm < v.min_spindle_rpm()) {
    return "valid from " + num(v.min_spindle_rpm()) + " rpm, the job runs at " + num(c.rpm);
  }
  if (v.max_spindle_rpm() > 0 && c.rpm > v.max_spindle_rpm()) {
    return "valid up to " + num(v.max_spindle_rpm()) + " rpm, the job runs at " + num(c.rpm);
  }
  if (v.min_width_mm() > 0 && c.width_mm < v.min_width_mm()) {
    return "valid from " + num(v.min_width_mm()) + " mm wide, the part is " + num(c.width_mm);
  }
  if (v.max_width_mm() > 0 && c.width_mm > v.max_width_mm()) {
    return "valid up to " + num(v.max_width_mm()) + " mm wide, the part is " + num(c.width_mm);
  }
  return {};
}

bool usable(const store::ProcessModel& m, const Cut& c) {
  return m.validated && m.suspect_reason.empty() && out_of_range(m, c).empty();
}

std::string describe(const store::ProcessModel& m, const Cut& c) {
  std::ostringstream o;
  const std::string range = out_of_range(m, c);
  o << store::kind_name(m.kind) << " model " << m.id << " (" << store::provenance_name(m.provenance)
    << (m.validated ? ", validated" : ", not validated")
    << (m.part_id.empty() ? "" : ", part " + m.part_id) << ", " << m.machine_id
    << (m.suspect_reason.empty() ? "" : ", suspect: " + m.suspect_reason)
    << (range.empty() ? "" : ", outside its validity range: " + range) << ")";
  return o.str();
}

// Why no model of this kind can be used.
std::string missing(const std::vector<store::ProcessModel>& models, store::ModelKind kind,
                    const char* name, const Cut& c) {
  for (const auto& m : models) {
    if (m.kind == kind && m.validated && !m.suspect_reason.empty()) {
      return std::string("the ") + name + " model " + m.id + " is suspect";
    }
  }
  for (const auto& m : models) {
    if (m.kind == kind && m.validated && !out_of_range(m, c).empty()) {
      return std::string("the ") + name + " model " + m.id + " is outside its validity range (" +
             out_of_range(m, c) + ")";
    }
  }
  return std::string("no validated ") + name + " model";
}

// A bound from the part's own cuts that may stand in for a structural
// model: a chatter-free depth cut for 20 revolutions or more, and no chatter
// at or below it.
bool usable_bound(const std::optional<StabilityBound>& b) {
  return b && b->stable_mm > 0 && b->revolutions >= 20 && !b->disagrees();
}

// The models on `machine` that make SMC I: validated and not suspect; a
// usable bound from the part's cuts stands in for the milling model.
struct Usable {
  std::optional<store::ProcessModel> force, milling;
  std::optional<StabilityBound> bound;
  bool smc1() const { return force && (milling || bound); }
};

Usable usable_on(const std::vector<store::ProcessModel>& models, const std::string& machine,
                 const Cut& c, const std::optional<StabilityBound>& bound) {
  Usable u;
  if (machine.empty()) return u;
  for (const auto& m : models) {
    if (!usable(m, c) || m.machine_id != machine) continue;
    if (m.kind == store::ModelKind::kForceProcess && !u.force) u.force = m;
    if (m.kind == store::ModelKind::kMilling && !u.milling) u.milling = m;
  }
  if (!u.milling && usable_bound(bound)) u.bound = bound;
  return u;
}

// Why these models do not make SMC I.
std::string why_not(const std::vector<store::ProcessModel>& models, const Usable& u, const Cut& c) {
  const std::string no_cuts =
      " and no chatter-free cut of the part at " + num(c.rpm) + " rpm to stand in for it";
  if (!u.force && !u.milling) {
    const std::string f = missing(models, store::ModelKind::kForceProcess, "force-process", c);
    const std::string m = missing(models, store::ModelKind::kMilling, "structural", c);
    return f == "no validated force-process model" && m == "no validated structural model"
               ? std::string("no validated models")
               : f + " and " + m;
  }
  if (!u.force) return missing(models, store::ModelKind::kForceProcess, "force-process", c);
  return missing(models, store::ModelKind::kMilling, "structural", c) + no_cuts;
}

std::string listing(const std::vector<store::ProcessModel>& models, const Cut& c) {
  std::string out;
  for (const auto& m : models) out += (out.empty() ? "" : "; ") + describe(m, c);
  return out.empty() ? "none" : out;
}

const char* const kSmc1Why =
    " (transfer line): a validated force-process model and a validated structural model of this "
    "machine exist, so the plan is made chatter-free by time-domain simulation and the force is "
    "held by the model-based controller.";
const char* const kSmc2Why =
    ", so the job runs as programmed with chatter detection and suppression and the adaptive "
    "force controller.";
const char* const kSmc2PlusWhy =
    ", so the job runs as programmed with the adaptive force controller; a first chatter in a "
    "pass moves the spindle to a stable pocket (module O) rather than adding a pass, because "
    "the part allows a speed change and this machine can override its spindle speed; a broken "
    "tooth stops the feed (module N).";

// Whether SMC II+ may run this job on this machine, and if not, why.
std::string smc2_plus_refusal(const PlanInputs& in) {
  if (!in.part.speed_change_allowed) {
    return "part " + in.part.id + " does not allow a spindle speed change";
  }
  if (in.machine.id.empty()) return "no machine was given";
  if (!machine_can_change_spindle_speed(in.machine)) {
    if (!drive_overrides_spindle_speed(in.machine.drive)) {
      return in.machine.id + "'s " + in.machine.drive + " drive cannot override its spindle speed";
    }
    return in.machine.id + "'s spindle has no speed range to move in (" +
           fmt(in.machine.min_spindle_rpm) + " to " + fmt(in.machine.max_spindle_rpm) + " rpm)";
  }
  return {};
}

}  // namespace

bool drive_overrides_spindle_speed(const std::string& drive) {
  // Both drives implement it: the simulated mill, and LinuxCNC's spindle
  // override (edge/README.md, module O).
  return drive.empty() || drive == "simulated" || drive == "linuxcnc";
}

bool machine_can_change_spindle_speed(const store::Machine& m) {
  // O skips a speed within 2 % of the present one: a spindle whose range is
  // narrower (a fixed-speed spindle) has nowhere to go. No maximum given:
  // no limit known.
  const bool range = m.max_spindle_rpm <= 0 || m.max_spindle_rpm > 1.02 * m.min_spindle_rpm;
  return drive_overrides_spindle_speed(m.drive) && range;
}

Selection select_variant(const PlanInputs& in) {
  Selection sel;
  std::ostringstream why;
  const std::string on = in.machine.id.empty() ? "any machine" : in.machine.id;
  why << "models on " << on << " for tool " << in.tool.id << " and material " << in.part.material_id
      << ": " << listing(in.models, cut_of(in)) << ". ";
  const Usable u = usable_on(in.models, in.machine.id, cut_of(in), in.bound);
  if (u.smc1() && u.milling) {
    sel.variant = smc::config::SMC_I;
    sel.force = u.force;
    sel.milling = u.milling;
    why << "SMC I on " << in.machine.id << kSmc1Why;
  } else if (u.smc1()) {
    sel.variant = smc::config::SMC_I;
    sel.force = u.force;
    sel.bound = u.bound;
    const auto& b = *u.bound;
    why << "SMC I on " << in.machine.id
        << " (transfer line, from the part's own cuts): a validated force-process model exists "
           "and, with no validated structural model, the part's cuts on "
        << in.machine.id << " at " << b.rpm << " rpm bound its stability: cut without chatter to "
        << fmt(b.stable_mm) << " mm (" << b.revolutions << " revolutions, " << b.jobs.size()
        << " job" << (b.jobs.size() == 1 ? "" : "s") << ")"
        << (b.has_chatter() ? ", chatter at " + fmt(b.chatter_mm) + " mm" : std::string())
        << "; so the passes stay within what was cut and the force is held by the model-based "
           "controller.";
  } else if (const std::string no_plus = smc2_plus_refusal(in); no_plus.empty()) {
    sel.variant = smc::config::SMC_II_PLUS;
    why << "SMC II+ on " << in.machine.id
        << " (job shop, extended): " << why_not(in.models, u, cut_of(in)) << kSmc2PlusWhy;
  } else {
    sel.variant = smc::config::SMC_II;
    why << "SMC II on " << on << " (job shop): "
        << (in.machine.id.empty() ? std::string("no machine was given")
                                  : why_not(in.models, u, cut_of(in)))
        << kSmc2Why;
    if (in.part.speed_change_allowed) why << " Not SMC II+: " << no_plus << ".";
  }
  sel.explanation = why.str();
  return sel;
}

Selection bind_and_select(PlanInputs& in, const std::vector<MachineModels>& machines) {
  const std::string& pinned = in.job.spec.machine_id();
  std::vector<const MachineModels*> order;
  for (const auto& m : machines) {
    if (pinned.empty() || m.machine.id == pinned) order.push_back(&m);
  }
  auto bind = [&in](const MachineModels& m) {
    in.machine = m.machine;
    in.models = m.models;
    in.bound = m.bound;
    return select_variant(in);
  };
  if (!pinned.empty()) {
    if (!order.empty()) return bind(*order.front());
    in.machine = {};
    in.models.clear();
    in.bound.reset();
    return select_variant(in);
  }
  // SMC I on an available machine; if none is available, on the first
  // machine that has the models (it waits for that machine).
  bool any_available = false;
  for (const MachineModels* m : order) any_available = any_available || m->available;
  for (const MachineModels* m : order) {
    if ((m->available || !any_available) &&
        usable_on(m->models, m->machine.id, cut_of(in), m->bound).smc1())
      return bind(*m);
  }
  // Else SMC II+ on an available machine that can override its spindle
  // speed, when the part allows a speed change.
  if (in.part.speed_change_allowed) {
    for (const MachineModels* m : order) {
      if ((m->available || !any_available) && machine_can_change_spindle_speed(m->machine))
        return bind(*m);
    }
  }
  // Else SMC II on whichever machine is free, each machine's reason given.
  in.machine = {};
  in.models.clear();
  in.bound.reset();
  std::ostringstream reasons;
  for (const MachineModels* m : order) {
    in.models.insert(in.models.end(), m->models.begin(), m->models.end());
    const Usable u = usable_on(m->models, m->machine.id, cut_of(in), m->bound);
    reasons << (m == order.front() ? "" : "; ") << m->machine.id << ": "
            << (u.smc1() ? std::string("has usable models but its edge is lost")
                         : why_not(m->models, u, cut_of(in)));
  }
  Selection sel;
  sel.variant = smc::config::SMC_II;
  std::ostringstream why;
  why << "models on every machine for tool " << in.tool.id << " and material "
      << in.part.material_id << ": " << listing(in.models, cut_of(in))
      << ". SMC II on any machine (job shop): "
      << (order.empty() ? std::string("no machines") : reasons.str()) << kSmc2Why;
  sel.explanation = why.str();
  return sel;
}

Planner::Planner(const std::string& grafcet_dir, smc::config::SupervisorConfig defaults,
                 PlannerOptions options)
    : smc1_text_(smc::documents::read_file(grafcet_dir + "/smc1.grafcet")),
      smc1_guarded_text_(smc::documents::read_file(grafcet_dir + "/smc1_guarded.grafcet")),
      smc2_text_(smc::documents::read_file(grafcet_dir + "/smc2.grafcet")),
      smc2_plus_text_(smc::documents::read_file(grafcet_dir + "/smc2_plus.grafcet")),
      defaults_(std::move(defaults)),
      options_(options) {}

namespace {

// Stable (no margin) at this depth and feed, by the time-domain criterion.
bool stable_at(const smc::machining::MillingModel& mach, double rpm, double fpt, double depth) {
  return smc::machining::assess_stability(mach, {rpm, fpt, depth}).verdict ==
         smc::machining::Verdict::stable;
}

}  // namespace

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
  const auto smc1_supervisor = [&] {
    if (options_.guard_smc1) {
      c.set_grafcet_name("smc1_guarded.grafcet");
      c.set_grafcet_text(smc1_guarded_text_);
      for (const char* m : {"A", "B", "C", "E", "F", "G", "I", "J", "L", "M"}) c.add_modules(m);
    } else {
      c.set_grafcet_name("smc1.grafcet");
      c.set_grafcet_text(smc1_text_);
      for (const char* m : {"A", "B", "C", "I", "J", "L", "M"}) c.add_modules(m);
    }
  };
  const auto guard_note = [&] {
    return options_.guard_smc1
               ? std::string(
                     " The chatter detector watches the cut (smc1_guarded): chatter means the "
                     "models are wrong; it is suppressed and the models are marked suspect.")
               : std::string();
  };
  if (sel.variant == smc::config::SMC_I && !sel.milling && sel.bound) {
    // From the part's own cuts: no structural model to simulate, so the
    // passes stay within the depth cut without chatter at this speed, the
    // controller's feed within the feeds it was cut at, and F_ref comes from
    // the measured spindle power (module M) rather than from a model.
    if (!sel.force || in.machine.id.empty()) {
      throw std::runtime_error("job " + in.job.id +
                               ": an SMC I plan needs the machine and its validated force model");
    }
    const auto& b = *sel.bound;
    out.machine_id = in.machine.id;
    out.model_ids = {sel.force->id};
    smc1_supervisor();
    *c.mutable_force_model() = sel.force->force;
    passes = std::max(1, static_cast<int>(std::ceil(job.depth_mm() / b.stable_mm - 1e-9)));
    if (passes > smc::supervision::kMaxPasses) {
      throw std::runtime_error("job " + in.job.id + ": passes no deeper than the " +
                               fmt(b.stable_mm) + " mm cut without chatter would need " +
                               std::to_string(passes) + " passes (at most " +
                               std::to_string(smc::supervision::kMaxPasses) + ")");
    }
    const double clamp0 = op->min_feed_per_tooth_mm();
    const double clamp = std::max(clamp0, std::min(b.stable_feed_mm, op->max_feed_per_tooth_mm()));
    op->set_min_feed_per_tooth_mm(clamp);
    out.programmed_feed_mm = smc::supervision::feed_per_tooth_mm(
        job.feedrate_mm_s(), static_cast<int>(in.tool.teeth), rpm);
    out.lower_clamp_mm = clamp;
    std::ostringstream why;
    why << c.explanation() << " " << passes << " equal pass" << (passes == 1 ? "" : "es") << " of "
        << fmt(job.depth_mm() / passes) << " mm, none deeper than the " << fmt(b.stable_mm)
        << " mm cut without chatter; the controller's lower feed clamp "
        << (clamp > clamp0
                ? "raised to " + fmt(clamp) + " mm/tooth, the lowest feed that cut was made at"
                : "at " + fmt(clamp) + " mm/tooth")
        << "; F_ref from the measured spindle power (module M): no structural model gives the "
           "cut's power."
        << guard_note();
    c.set_explanation(why.str());
  } else if (sel.variant == smc::config::SMC_I) {
    if (!sel.force || !sel.milling || in.machine.id.empty()) {
      throw std::runtime_error("job " + in.job.id +
                               ": an SMC I plan needs the machine and its validated models");
    }
    out.machine_id = in.machine.id;
    out.model_ids = {sel.force->id, sel.milling->id};
    smc1_supervisor();
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
    const double margin = options_.margin;
    double allowed = margin * out.critical_depth_mm;
    // No pass deeper than the models were made for (their validity range).
    std::string depth_note;
    for (const auto* pm : {&*sel.force, &*sel.milling}) {
      const double max_depth = pm->validity.max_depth_mm();
      if (max_depth > 0 && max_depth < allowed) {
        allowed = max_depth;
        depth_note = " Passes no deeper than " + num(max_depth) + " mm: model " + pm->id +
                     " is valid to that depth.";
      }
    }
    const int first = std::max(1, static_cast<int>(std::ceil(job.depth_mm() / allowed - 1e-9)));
    auto too_many = [&](int n, const std::string& why) {
      return std::runtime_error("job " + in.job.id + ": " + why + " would need " +
                                std::to_string(n) + " passes (at most " +
                                std::to_string(smc::supervision::kMaxPasses) + ")");
    };
    if (first > smc::supervision::kMaxPasses) {
      throw too_many(first, "the critical depth " + fmt(out.critical_depth_mm) + " mm");
    }
    // The feeds the model-based controller may command on this machine: it
    // starts at min(programmed, equilibrium), settles at the eq. 1
    // equilibrium feed for the pass's F_ref, and in transients may go down
    // to its lower clamp. With power-law pressures the critical depth falls
    // with the feed, so the pass must be stable with the margin at the
    // lowest steady feed and stable (no margin) at the clamp; the clamp is
    // raised for that, up to max_clamp_share of the steady feed, before a
    // pass is added.
    const auto& fm = sel.force->force;
    const double clamp0 = op->min_feed_per_tooth_mm();
    const double fmax = op->max_feed_per_tooth_mm();
    std::string feed_note;
    for (passes = first;; ++passes) {
      if (passes > smc::supervision::kMaxPasses) {
        throw too_many(passes, "keeping every pass stable at the feeds the controller commands");
      }
      const double depth = job.depth_mm() / passes;
      const double fref = force_reference_n(c, in.machine.max_spindle_power_w, depth, rpm, fpt);
      const double feq = std::clamp(
          std::pow(fref / (1000.0 * fm.k_kn() * std::pow(depth, fm.beta())), 1.0 / fm.alpha()),
          clamp0, fmax);
      const double steady = std::min(fpt, feq);
      if (steady < fpt && !stable_at(mach, rpm, steady, depth / margin)) continue;
      double clamp = clamp0;
      if (!stable_at(mach, rpm, clamp0, depth)) {
        // Lowest stable feed in [clamp0, share x steady], by bisection
        // (the critical depth grows with the feed).
        double hi = options_.max_clamp_share * steady;
        if (hi <= clamp0 || !stable_at(mach, rpm, hi, depth)) continue;
        double lo = clamp0;
        while (hi - lo > 0.02 * hi) {
          const double mid = 0.5 * (lo + hi);
          (stable_at(mach, rpm, mid, depth) ? hi : lo) = mid;
        }
        clamp = hi;
      }
      op->set_min_feed_per_tooth_mm(clamp);
      out.programmed_feed_mm = fpt;
      out.equilibrium_feed_mm = feq;
      out.lower_clamp_mm = clamp;
      std::ostringstream n;
      n << " Feeds checked on " << in.machine.id << ": programmed " << fmt(fpt)
        << " mm/tooth, equilibrium " << fmt(feq) << " mm/tooth at F_ref " << fmt(fref)
        << " N (eq. 1); " << fmt(depth) << " mm passes are stable with the margin at "
        << fmt(steady) << " mm/tooth and down to the controller's lower clamp of " << fmt(clamp)
        << " mm/tooth"
        << (clamp > clamp0 ? " (raised from " + fmt(clamp0) + ": the lowest stable feed)" : "")
        << (passes > first ? "; " + std::to_string(passes - first) +
                                 " pass(es) added for the feeds below the programmed one"
                           : "")
        << ".";
      feed_note = n.str();
      break;
    }
    std::ostringstream why;
    why << c.explanation() << " Critical depth at " << rpm << " rpm on " << in.machine.id << ": "
        << fmt(out.critical_depth_mm) << " mm; with a " << margin << " margin, " << passes
        << " equal pass" << (passes == 1 ? "" : "es") << " of " << fmt(job.depth_mm() / passes)
        << " mm." << depth_note << feed_note << guard_note();
    c.set_explanation(why.str());
  } else if (sel.variant == smc::config::SMC_II_PLUS) {
    if (in.machine.id.empty()) {
      throw std::runtime_error("job " + in.job.id +
                               ": an SMC II+ plan needs the machine whose spindle it moves");
    }
    out.machine_id = in.machine.id;
    c.set_grafcet_name("smc2_plus.grafcet");
    c.set_grafcet_text(smc2_plus_text_);
    for (const char* m : {"A", "B", "C", "D", "E", "F", "G", "H", "I", "J", "K", "M", "N", "O"}) {
      c.add_modules(m);
    }
  } else {
    c.set_grafcet_name("smc2.grafcet");
    c.set_grafcet_text(smc2_text_);
    for (const char* m : {"A", "B", "C", "D", "E", "F", "G", "H", "I", "J", "K", "M"}) {
      c.add_modules(m);
    }
  }
  // A job-shop run (SMC II or SMC II+) of a part with no validated force
  // model carries an identification segment, so that its revolutions hold
  // F_Y at more than one level and the cell can fit the model's exponents
  // (learning.hpp). The edge ramps F_ref between the levels, so that module
  // N does not read the change as a broken tooth.
  const bool job_shop =
      sel.variant == smc::config::SMC_II || sel.variant == smc::config::SMC_II_PLUS;
  if (job_shop && options_.identification_revolutions > 0) {
    bool validated_force = false;
    for (const auto& m : in.models) {
      validated_force =
          validated_force || (m.kind == store::ModelKind::kForceProcess && m.validated &&
                              m.suspect_reason.empty() && m.part_id == in.part.id);
    }
    if (!validated_force) {
      std::ostringstream levels;
      for (const double l : options_.identification_levels) {
        op->add_identification_levels(l);
        levels << (levels.tellp() > 0 ? ", " : "") << std::lround(100 * l) << " %";
      }
      op->set_identification_revolutions(options_.identification_revolutions);
      c.set_explanation(c.explanation() + " Identification segment: part " + in.part.id +
                        " has no validated force model, so in the last pass, 20 revolutions "
                        "after contact, F_ref ramps (at most 2.5 % a revolution) to " +
                        levels.str() + " of itself and holds each for " +
                        std::to_string(options_.identification_revolutions) +
                        " revolutions, and the cell fits the model's exponents from "
                        "the forces at each level.");
    }
  }
  for (int i = 0; i < passes; ++i) {
    auto* p = prog->add_passes();
    p->set_depth_mm(job.depth_mm() / passes);
    p->set_feedrate_mm_s(job.feedrate_mm_s());
    p->set_spindle_rpm(rpm);
  }
  prog->set_gcode(smc::supervision::render_gcode(
      c, {.title = "job " + in.job.id + ", part " + in.part.id + ", " +
                   std::string(store::variant_name(sel.variant)) +
                   (out.machine_id.empty() ? "" : " for " + out.machine_id)}));
  out.planning_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

namespace {

// Module E's structure for a plan that has none in y (for_machine).
void give_e_a_structure(smc::config::SupervisorConfig& c, const store::Machine& machine,
                        const store::ProcessModel* structure) {
  // SMC I brings its model's structure; a plan without E needs none.
  if (!smc::supervision::chatter_detector_without_structure(c)) return;
  auto* st = c.mutable_milling_model()->mutable_structure();
  std::ostringstream why;
  if (structure == nullptr) {
    why << " Module E has no structure of " << machine.id
        << " with this tool, so it judges the force spectrum alone (S, edge/CHATTER.md); a "
           "tap test (`smc-cell model fit-frf`) gives it the vibration estimate.";
  } else {
    // The whole structure, the part's modes too where they are another
    // part's: without them E's estimate misses the part's compliance and
    // reads q 1.2-1.8 times the mill's (edge/CHATTER.md, "The structure E
    // is given"), worse than any error in them that was measured.
    *st = structure->milling.structure();
    const bool parts_own =
        structure->part_id.empty() || structure->part_id == c.program().part_id();
    why << " Module E estimates the vibration with " << machine.id << "'s structure from model "
        << structure->id << " (" << store::provenance_name(structure->provenance)
        << (structure->suspect_reason.empty() ? "" : ", suspect") << ")"
        << (parts_own ? ""
                      : ", the part's modes being part " + structure->part_id +
                            "'s: a tap test of this part on its fixture gives its own")
        << ".";
  }
  c.set_explanation(c.explanation() + why.str());
}

// The machine's wideband F_y channel, where its record gives one, in place
// of the cell's default: E undoes that channel's filter and noise and takes
// the rules for its rate, and a simulated mill samples it so.
void use_the_machines_channel(smc::config::SupervisorConfig& c, const store::Machine& machine) {
  const auto& w = machine.wideband;
  if (w.is_default()) return;
  auto* op = c.mutable_operation();
  op->set_wideband_samples_per_tick(w.samples_per_tick);
  op->set_wideband_cutoff_hz(w.cutoff_hz);
  op->set_wideband_filter_order(w.filter_order);
  op->set_wideband_noise_rms_n(w.noise_rms_n);
  auto* sim = c.mutable_simulation();
  sim->set_f_y_wide_samples_per_tick(w.samples_per_tick);
  sim->set_f_y_wide_cutoff_hz(w.cutoff_hz);
  sim->set_f_y_wide_order(w.filter_order);
  sim->set_f_y_wide_noise_rms_n(w.noise_rms_n);
  const double period =
      c.operation().sample_period_s() > 0 ? c.operation().sample_period_s() : 5e-4;
  const double rate_hz = w.samples_per_tick / period;
  std::ostringstream why;
  why << " Module E reads " << machine.id << "'s wideband channel: " << std::setprecision(3)
      << rate_hz / 1000 << " kHz through an order-" << w.filter_order << " filter at "
      << std::setprecision(6) << w.cutoff_hz << " Hz"
      << (rate_hz < smc::supervision::kFineChannelRateHz * (1 - 1e-9)
              ? ", with the rules chosen at 2 kHz (which catch fewer onsets within 3 "
                "revolutions than the 10 kHz channel's: cell/README.md)"
              : "")
      << ".";
  c.set_explanation(c.explanation() + why.str());
}

}  // namespace

std::string Planner::structure_note(const smc::config::SupervisorConfig& plan,
                                    const store::ProcessModel* structure) {
  if (!smc::supervision::chatter_detector_without_structure(plan)) return {};
  return structure != nullptr
             ? "module E with the structure of model " + structure->id
             : std::string(
                   "module E on the force spectrum alone (no structure of this machine "
                   "with the tool)");
}

smc::config::SupervisorConfig Planner::for_machine(const smc::config::SupervisorConfig& plan,
                                                   const store::Machine& machine,
                                                   const std::string& config_id,
                                                   const store::ProcessModel* structure) {
  smc::config::SupervisorConfig c = plan;
  c.set_config_id(config_id);
  give_e_a_structure(c, machine, structure);
  use_the_machines_channel(c, machine);
  auto* m = c.mutable_machine();
  m->set_machine_id(machine.id);
  m->set_max_spindle_power_w(machine.max_spindle_power_w);
  m->set_max_feedrate_mm_s(machine.max_feedrate_mm_s);
  m->set_max_spindle_rpm(machine.max_spindle_rpm);
  // SMC I: each pass's F_ref from the models, for this machine's power.
  plan_force_references(c);
  // The G-code for this machine: F capped by its max feedrate.
  if (!c.program().gcode().empty()) {
    c.mutable_program()->set_gcode(smc::supervision::render_gcode(
        c,
        {.title = "configuration " + config_id + " for " + machine.id + ", part " +
                  c.program().part_id() + ", " + std::string(store::variant_name(c.variant()))}));
  }
  // A channel that hides the chatter of the structure E now has
  // (edge/CHATTER.md, "What the channel's filter costs E"); the whole
  // configuration, machine limits included, is read for it.
  if (const auto w = smc::supervision::wideband_channel_warning(c); !w.empty()) {
    c.set_explanation(c.explanation() + " Warning on " + machine.id + ": " + w + ".");
  }
  return c;
}

}  // namespace smc::cell
