// CellState, recording: what the DDS thread hands in becomes state and the
// events the browser stream carries.

#include "cell_state_impl.hpp"

namespace smc::dashboard {

CellState::CellState(StateLimits limits) : impl_(std::make_unique<Impl>()) {
  impl_->limits = limits;
}
CellState::~CellState() = default;

std::vector<Event> CellState::on_summary(const smc_data_ForceSummary& s, std::int64_t src_unix_ns) {
  std::vector<Event> events;
  const std::string id = get_string(s.machine_id);
  JsonWriter w;
  w.begin_object()
      .field("machine_id", id)
      .field("t", seconds(s.machine_time_ns))
      .field("machine_time_ns", std::to_string(s.machine_time_ns))
      .field("revolution", s.revolution)
      .field("pass_index", s.pass_index)
      .field("pass_count", s.pass_count)
      .field("f_y_peak_n", s.f_y_peak_n)
      .field("f_ref_n", s.f_ref_n)
      .field("feedrate_mm_s", s.feedrate_mm_s)
      .field("feed_per_tooth_mm", s.feed_per_tooth_mm)
      .field("depth_mm", s.depth_mm)
      .field("spindle_rpm", s.spindle_rpm)
      .field("spindle_power_w", s.spindle_power_w)
      .field("in_contact", s.in_contact)
      .field("chatter", s.chatter)
      .field("src_unix_ms", unix_ms(src_unix_ns))
      .end_object();
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  m->summary_json = w.str();
  SummaryPoint p;
  p.t = seconds(s.machine_time_ns);
  p.f_y = s.f_y_peak_n;
  p.f_ref = s.f_ref_n;
  p.feed = s.feedrate_mm_s;
  p.power = s.spindle_power_w;
  p.pass_index = s.pass_index;
  p.pass_count = s.pass_count;
  p.contact = s.in_contact;
  p.chatter = s.chatter;
  push_bounded(m->history, p, impl_->limits.history_revolutions);
  events.push_back(make_event(EventKind::kSummary, id, w.str()));
  return events;
}

std::vector<Event> CellState::on_batch(const smc_data_ForceBatch& b, std::int64_t src_unix_ns) {
  std::vector<Event> events;
  const std::string id = get_string(b.machine_id);
  const std::size_t n = std::min<std::size_t>(b.count, wire::kForceBatchMax);
  JsonWriter w;
  w.begin_object()
      .field("machine_id", id)
      .field("t0", seconds(b.first_sample_time_ns))
      .field("dt", static_cast<double>(b.sample_period_ns) * 1e-9)
      .field("decimation", b.decimation)
      .field("src_unix_ms", unix_ms(src_unix_ns));
  w.key("f_y_n").begin_array();
  for (std::size_t i = 0; i < n; ++i) w.value(b.f_y_n[i]);
  w.end_array().key("f_z_n").begin_array();
  for (std::size_t i = 0; i < n; ++i) w.value(b.f_z_n[i]);
  w.end_array().end_object();
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  push_bounded(m->batches, w.str(), impl_->limits.batches);
  events.push_back(make_event(EventKind::kBatch, id, w.str()));
  return events;
}

std::vector<Event> CellState::on_situation(const smc_data_SupervisorSituation& s,
                                           std::int64_t src_unix_ns) {
  std::vector<Event> events;
  const std::string id = get_string(s.machine_id);
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  m->situation =
      SituationRaw{s.machine_time_ns, s.sequence_number,       s.active_steps, s.modules_active,
                   s.inputs,          get_string(s.config_id), src_unix_ns};
  m->situation_json = impl_->render_situation(*m);
  push_bounded(m->situations,
               SituationPoint{seconds(s.machine_time_ns), s.active_steps, s.modules_active},
               impl_->limits.situations);
  events.push_back(make_event(EventKind::kSituation, id, m->situation_json));
  return events;
}

std::vector<Event> CellState::on_status(const smc_data_EdgeStatus& s) {
  std::vector<Event> events;
  const std::string id = get_string(s.machine_id);
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  m->online = true;
  m->status_json = impl_->render_status(*m, &s);
  const std::string job = get_string(s.job_id);
  if (!job.empty()) m->job_id = job;
  events.push_back(make_event(EventKind::kStatus, id, m->status_json));
  m->reported_config = get_string(s.config_id);
  adopt_config(*m, m->reported_config, events);
  return events;
}

std::vector<Event> CellState::on_edge_gone(const std::string& machine_id) {
  std::vector<Event> events;
  std::lock_guard lock(impl_->mu);
  auto it = impl_->mills.find(machine_id);
  if (it == impl_->mills.end() || !it->second.online) return events;
  Mill& m = it->second;
  m.online = false;
  m.status_json = impl_->render_status(m, nullptr);
  events.push_back(make_event(EventKind::kStatus, machine_id, m.status_json));
  return events;
}

std::vector<Event> CellState::on_chatter(const smc_data_ChatterEvent& e) {
  std::vector<Event> events;
  const std::string id = get_string(e.machine_id);
  JsonWriter w;
  w.begin_object().field("machine_id", id);
  write_id(w, "event_id", e.event_id);
  w.field("t", seconds(e.machine_time_ns))
      .field("machine_time_ns", std::to_string(e.machine_time_ns))
      .field("source", e.source == smc_data_CHATTER_OPERATOR ? "operator" : "automatic")
      .field("frequency_hz", e.frequency_hz)
      .field("energy_ratio", e.energy_ratio)
      .field("pass_index", e.pass_index)
      .field("new_pass_count", e.new_pass_count)
      .field("new_spindle_rpm", e.new_spindle_rpm)
      .field("job_id", get_string(e.job_id))
      .end_object();
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  if (!m->chatter_seen.insert(e.event_id).second) return events;  // a repeat
  ++m->chatter_total;
  push_bounded(m->chatter, w.str(), impl_->limits.chatter_events);
  events.push_back(make_event(EventKind::kChatter, id, w.str()));
  return events;
}

std::vector<Event> CellState::on_progress(const smc_data_JobProgress& p) {
  std::vector<Event> events;
  const std::string id = get_string(p.machine_id);
  const std::string job_id = get_string(p.job_id);
  JsonWriter w;
  w.begin_object()
      .field("machine_id", id)
      .field("job_id", job_id)
      .field("t", seconds(p.machine_time_ns))
      .field("sequence_number", p.sequence_number)
      .field("phase", wire::job_phase_name(static_cast<int>(p.phase)))
      .field("pass_index", p.pass_index)
      .field("pass_count", p.pass_count)
      .field("depth_removed_mm", p.depth_removed_mm)
      .field("fraction_done", p.fraction_done)
      .field("chatter_events", p.chatter_events)
      .field("peak_force_n", p.peak_force_n)
      .field("message", get_string(p.message))
      .end_object();
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  events.push_back(make_event(EventKind::kProgress, id, w.str()));
  if (job_id.empty()) return events;
  m->job_id = job_id;
  Job& j = impl_->job(job_id);
  j.machine_id = id;
  j.progress_json = w.take();
  if (p.phase == smc_data_JOB_DONE || p.phase == smc_data_JOB_FAILED) j.finished = true;
  return events;
}

std::vector<Event> CellState::on_config(const std::string& machine_id,
                                        const config::SupervisorConfig& c) {
  std::vector<Event> events;
  GrafcetView view = make_grafcet_view(c.grafcet_text(), "smc_config/" + machine_id);
  JsonWriter w;
  w.begin_object()
      .field("machine_id", machine_id)
      .field("config_id", c.config_id())
      .field("variant", config::SmcVariant_Name(c.variant()))
      .field("grafcet_name", c.grafcet_name());
  w.key("modules").begin_array();
  for (const auto& mod : c.modules()) w.value(mod);
  w.end_array()
      .field("explanation", c.explanation())
      .field("force_reference_n", c.operation().force_reference_n())
      .field("max_spindle_power_w", c.machine().max_spindle_power_w())
      .field("part_id", c.program().part_id())
      .field("passes", c.program().passes_size());
  w.key("grafcet").raw(view.json).end_object();
  std::string doc = documents::to_json(c, false);
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(machine_id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  constexpr std::size_t kCandidates = 4;
  auto& cand = m->candidates[c.config_id()];
  cand = Mill::Candidate{std::move(view), w.take(), std::move(doc), ++m->candidate_order};
  while (m->candidates.size() > kCandidates) {  // forget the oldest
    auto oldest = m->candidates.begin();
    for (auto it = m->candidates.begin(); it != m->candidates.end(); ++it) {
      if (it->second.order < oldest->second.order) oldest = it;
    }
    m->candidates.erase(oldest);
  }
  // In force only once the edge says so (it may already have: statuses and
  // documents arrive in any order).
  if (c.config_id() == m->config_in_force) m->config_in_force.clear();  // new content
  adopt_config(*m, m->reported_config, events);
  return events;
}

void CellState::adopt_config(Mill& m, const std::string& config_id, std::vector<Event>& events) {
  if (config_id.empty() || config_id == m.config_in_force) return;
  auto it = m.candidates.find(config_id);
  if (it == m.candidates.end()) return;  // not seen yet: adopted when it arrives
  m.config_in_force = config_id;
  m.grafcet = it->second.grafcet;
  m.has_grafcet = true;
  m.config_brief_json = it->second.brief_json;
  m.config_doc_json = it->second.doc_json;
  events.push_back(make_event(EventKind::kConfig, m.id, m.config_brief_json));
  if (m.situation) {  // step numbers and input names may have changed
    m.situation_json = impl_->render_situation(m);
    events.push_back(make_event(EventKind::kSituation, m.id, m.situation_json));
  }
}

std::vector<Event> CellState::on_program(const std::string& machine_id,
                                         const config::PartProgram& p) {
  std::vector<Event> events;
  JsonWriter w;
  w.begin_object().field("machine_id", machine_id);
  w.key("program").raw(documents::to_json(p, false)).end_object();
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(machine_id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  m->program_json = w.str();
  events.push_back(make_event(EventKind::kProgram, machine_id, w.str()));
  return events;
}

std::vector<Event> CellState::on_job(const std::string& job_id, const config::JobStatus& js) {
  std::vector<Event> events;
  std::string doc = documents::to_json(js, false);
  std::lock_guard lock(impl_->mu);
  ++impl_->counters.samples;
  Job& j = impl_->job(job_id);
  j.status_doc = std::move(doc);
  if (!js.machine_id().empty()) j.machine_id = js.machine_id();
  j.finished = js.state() == config::JOB_DONE || js.state() == config::JOB_FAILED;
  events.push_back(impl_->job_event(job_id, j));
  return events;
}

std::vector<Event> CellState::on_catalog(const config::CatalogView& view) {
  std::vector<Event> events;
  std::string doc = documents::to_json(view, false);
  std::lock_guard lock(impl_->mu);
  ++impl_->counters.samples;
  impl_->catalog = doc;
  events.push_back(make_event(EventKind::kCatalog, {}, doc));
  return events;
}

std::vector<Event> CellState::on_command(const CommandRecord& record) {
  std::vector<Event> events;
  std::string json = to_json(record);
  std::lock_guard lock(impl_->mu);
  push_bounded(impl_->commands, json, impl_->limits.commands);
  events.push_back(make_event(EventKind::kCommand, record.request.machine_id, json));
  return events;
}

}  // namespace smc::dashboard
