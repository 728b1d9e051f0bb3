#include "job_history.hpp"

#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "json.hpp"
#include "smc/cell/store/store.hpp"
#include "smc/machining/lobes.hpp"
#include "smc/machining/model_proto.hpp"

namespace smc::dashboard {

namespace {

std::string proto_json(const google::protobuf::Message& m) {
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.preserve_proto_field_names = true;
  if (!google::protobuf::util::MessageToJsonString(m, &out, o).ok()) return "null";
  return out;
}

// One column of the recorded revolutions.
template <class F>
void column(JsonWriter& w, std::string_view name,
            const std::vector<cell::store::JobRevolution>& revs, F get) {
  w.key(name).begin_array();
  for (const auto& r : revs) w.value(get(r));
  w.end_array();
}

}  // namespace

JobHistory::JobHistory(std::string db_path) : path_(std::move(db_path)) {}

cell::store::Store& JobHistory::db() {
  if (!db_) {
    db_ = std::make_unique<cell::store::Store>(
        cell::store::Store::open(path_, cell::store::OpenMode::kExisting));
  }
  return *db_;
}

JobHistory::~JobHistory() = default;

std::optional<std::string> JobHistory::json(const std::string& job_id) {
  std::lock_guard lock(mu_);
  const auto j = db().job(job_id);
  if (!j) return std::nullopt;
  const auto revs = db().revolutions(job_id);
  const auto programs = db().programs(job_id);
  const auto events = db().events(job_id);
  JsonWriter w;
  w.begin_object()
      .field("job_id", j->id)
      .field("part_id", j->spec.part_id())
      .field("tool_id", j->spec.tool_id())
      .field("machine_id", j->machine_id)
      .field("state", cell::store::state_name(j->state))
      .field("variant", cell::store::variant_name(j->variant))
      .field("explanation", j->explanation)
      .field("attempt", j->attempt)
      .field("created_at_ms", j->created_at_ms)
      .field("updated_at_ms", j->updated_at_ms);
  const auto machine = j->machine_id.empty() ? std::nullopt : db().machine(j->machine_id);
  w.field("max_spindle_power_w", machine ? machine->max_spindle_power_w : 0.0);
  w.key("job").raw(proto_json(j->spec));
  w.key("plan");
  if (j->plan) {
    w.begin_object()
        .field("grafcet_name", j->plan->grafcet_name())
        .field("gcode", j->plan->program().gcode());
    w.key("modules").begin_array();
    for (const auto& m : j->plan->modules()) w.value(m);
    w.end_array();
    w.key("passes").begin_array();
    for (const auto& p : j->plan->program().passes()) {
      w.begin_object()
          .field("depth_mm", p.depth_mm())
          .field("feedrate_mm_s", p.feedrate_mm_s())
          .field("spindle_rpm", p.spindle_rpm())
          .field("force_reference_n", p.force_reference_n())
          .end_object();
    }
    w.end_array();
    // SMC I: the structural model the plan was checked against (lobes).
    w.field("has_structural_model", j->variant == smc::config::SMC_I &&
                                        j->plan->has_milling_model() &&
                                        j->plan->milling_model().has_structure());
    w.end_object();
  } else {
    w.null();
  }
  w.key("result");
  if (j->result) {
    w.raw(proto_json(*j->result));
  } else {
    w.null();
  }
  w.key("events").begin_array();
  for (const auto& e : events) {
    w.begin_object()
        .field("time_ms", e.time_ms)
        .field("from", cell::store::state_name(e.from_state))
        .field("to", cell::store::state_name(e.to_state))
        .field("note", e.is_note())
        .field("reason", e.reason)
        .field("machine_id", e.machine_id)
        .end_object();
  }
  w.end_array();
  w.key("programs").begin_array();
  for (const auto& p : programs) {
    w.begin_object()
        .field("attempt", p.attempt)
        .field("revision", p.revision)
        .field("time_ms", p.time_ms)
        .field("passes", p.passes)
        .field("gcode", p.gcode)
        .end_object();
  }
  w.end_array();
  using R = cell::store::JobRevolution;
  w.key("revolutions").begin_object().field("count", revs.size());
  column(w, "attempt", revs, [](const R& r) { return r.attempt; });
  column(w, "t", revs, [](const R& r) { return r.t_s; });
  column(w, "pass_index", revs, [](const R& r) { return r.pass_index; });
  column(w, "pass_count", revs, [](const R& r) { return r.pass_count; });
  column(w, "depth_mm", revs, [](const R& r) { return r.depth_mm; });
  column(w, "f_y_peak_n", revs, [](const R& r) { return r.f_y_n; });
  column(w, "f_ref_n", revs, [](const R& r) { return r.f_ref_n; });
  column(w, "feedrate_mm_s", revs, [](const R& r) { return r.feedrate_mm_s; });
  column(w, "spindle_rpm", revs, [](const R& r) { return r.spindle_rpm; });
  column(w, "spindle_power_w", revs, [](const R& r) { return r.spindle_power_w; });
  column(w, "in_contact", revs, [](const R& r) { return r.in_contact; });
  column(w, "chatter", revs, [](const R& r) { return r.chatter; });
  w.end_object();
  w.end_object();
  return w.take();
}

std::optional<std::string> JobHistory::csv(const std::string& job_id) {
  std::lock_guard lock(mu_);
  if (!db().job(job_id)) return std::nullopt;
  std::string out =
      "job_id,attempt,t_s,revolution,pass,pass_count,depth_mm,f_y_peak_n,f_ref_n,feedrate_mm_s,"
      "feed_per_tooth_mm,spindle_rpm,spindle_power_w,in_contact,chatter\n";
  char line[320];
  for (const auto& r : db().revolutions(job_id)) {
    const int n = std::snprintf(
        line, sizeof line, ",%u,%.6f,%u,%u,%u,%.4f,%.3f,%.3f,%.4f,%.6f,%.2f,%s,%d,%d\n", r.attempt,
        r.t_s, r.revolution, r.pass_index + 1, r.pass_count, r.depth_mm, r.f_y_n, r.f_ref_n,
        r.feedrate_mm_s, r.feed_per_tooth_mm, r.spindle_rpm,
        std::isfinite(r.spindle_power_w) ? std::to_string(std::lround(r.spindle_power_w)).c_str()
                                         : "",
        r.in_contact ? 1 : 0, r.chatter ? 1 : 0);
    out += job_id;
    out.append(line, static_cast<std::size_t>(std::max(0, n)));
  }
  return out;
}

std::optional<std::string> JobHistory::lobes(const std::string& job_id) {
  std::optional<cell::store::Job> j;
  {
    std::lock_guard lock(mu_);
    j = db().job(job_id);
  }
  if (!j) return std::nullopt;
  JsonWriter w;
  w.begin_object();
  if (j->variant != smc::config::SMC_I || !j->plan || !j->plan->has_milling_model() ||
      !j->plan->milling_model().has_structure() || j->plan->program().passes_size() == 0) {
    w.key("lobes").null().field("why", "only an SMC I plan has a structural model to draw");
    w.end_object();
    return w.take();
  }
  const auto& plan = *j->plan;
  const auto& pass = plan.program().passes(0);
  const double rpm = pass.spindle_rpm();
  const int teeth = static_cast<int>(plan.milling_model().cutter().teeth());
  const double fpt = rpm > 0 && teeth > 0 ? pass.feedrate_mm_s() * 60.0 / (teeth * rpm) : 0.1;
  try {
    const auto model = smc::machining::from_proto(plan.milling_model(), job_id);
    smc::machining::LobeOptions o;
    o.rpm_min = 0.5 * rpm;
    o.rpm_max = 2.0 * rpm;
    o.speeds = 120;
    o.feed_per_tooth_mm = fpt;
    const auto lobes = smc::machining::stability_lobes(model, o);
    w.field("planned_rpm", rpm).field("feed_per_tooth_mm", fpt);
    w.key("planned_depths_mm").begin_array();
    for (const auto& p : plan.program().passes()) w.value(p.depth_mm());
    w.end_array();
    w.key("lobes").begin_object();
    w.key("rpm").begin_array();
    for (const auto& p : lobes) w.value(p.spindle_rpm);
    w.end_array().key("critical_depth_mm").begin_array();
    for (const auto& p : lobes) w.value(p.critical_depth_mm);
    w.end_array().end_object();
  } catch (const std::exception& e) {
    w.key("lobes").null().field("why", std::string("the plan's model: ") + e.what());
  }
  w.end_object();
  return w.take();
}

}  // namespace smc::dashboard
