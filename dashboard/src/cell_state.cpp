#include "cell_state.hpp"

#include <algorithm>
#include <deque>
#include <map>
#include <set>

#include "grafcet_view.hpp"
#include "json.hpp"
#include "smc/documents/load.hpp"
#include "smc/wire/names.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::dashboard {

namespace {

using wire::get_string;

constexpr const char kModuleLetters[] = "ABCDEFGHIJKL";
constexpr std::uint64_t kMaxExactJs = std::uint64_t{1} << 53;

double seconds(std::uint64_t ns) { return static_cast<double>(ns) * 1e-9; }
double unix_ms(std::int64_t ns) { return static_cast<double>(ns) * 1e-6; }

// A 64-bit id as a JSON number when a browser holds it exactly, else a string.
void write_id(JsonWriter& w, std::string_view key, std::uint64_t v) {
  w.key(key);
  if (v < kMaxExactJs) {
    w.value(v);
  } else {
    w.value(std::to_string(v));
  }
}

std::string module_letters(std::uint32_t mask) {
  std::string out;
  for (unsigned i = 0; i < 12; ++i) {
    if ((mask >> i) & 1U) out.push_back(kModuleLetters[i]);
  }
  return out;
}

template <class T>
void push_bounded(std::deque<T>& d, T v, std::size_t cap) {
  d.push_back(std::move(v));
  while (d.size() > cap) d.pop_front();
}

void write_string_array(JsonWriter& w, const std::deque<std::string>& items, std::size_t last_n) {
  w.begin_array();
  const std::size_t start = items.size() > last_n ? items.size() - last_n : 0;
  for (std::size_t i = start; i < items.size(); ++i) w.raw(items[i]);
  w.end_array();
}

void raw_or_null(JsonWriter& w, std::string_view key, const std::string& json) {
  w.key(key);
  if (json.empty()) {
    w.null();
  } else {
    w.raw(json);
  }
}

struct SummaryPoint {
  double t = 0;
  float f_y = 0;
  float f_ref = 0;
  float feed = 0;
  std::uint16_t pass_index = 0;
  std::uint16_t pass_count = 0;
  bool contact = false;
  bool chatter = false;
};

struct SituationPoint {
  double t = 0;
  std::uint64_t steps = 0;
  std::uint32_t modules = 0;
};

struct SituationRaw {
  std::uint64_t machine_time_ns = 0;
  std::uint32_t sequence_number = 0;
  std::uint64_t active_steps = 0;
  std::uint32_t modules_active = 0;
  std::uint32_t inputs = 0;
  std::string config_id;
  std::int64_t src_unix_ns = 0;
};

}  // namespace

struct CellState::Mill {
  std::string id;
  bool online = false;
  std::string status_json;
  std::string summary_json;
  std::string situation_json;
  std::optional<SituationRaw> situation;
  std::string program_json;
  std::string config_brief_json;  // with the Grafcet model
  std::string config_doc_json;    // the whole SupervisorConfig (Protobuf JSON mapping)
  GrafcetView grafcet;
  bool has_grafcet = false;
  std::deque<SummaryPoint> history;
  std::deque<SituationPoint> situations;
  std::deque<std::string> batches;
  std::deque<std::string> chatter;
  std::uint64_t chatter_total = 0;
  // Event ids seen: an edge's transient-local writer delivers its events
  // again after a reconnection (a cut link, a restarted dashboard), and an
  // event must count once.
  std::set<std::uint64_t> chatter_seen;
  std::string job_id;  // latest job reported by JobProgress / EdgeStatus
};

struct CellState::Job {
  std::string status_doc;  // JobStatus (Protobuf JSON mapping)
  std::string progress_json;
  std::string machine_id;
  std::uint64_t order = 0;  // first seen
  bool finished = false;
};

struct CellState::Impl {
  StateLimits limits;
  mutable std::mutex mu;
  std::map<std::string, Mill> mills;
  std::map<std::string, Job> jobs;
  std::uint64_t job_order = 0;
  std::deque<std::string> commands;
  Counters counters;

  // The mill, created (with a kMill event) on first sight; null past the limit.
  Mill* mill(const std::string& id, std::vector<Event>& events) {
    auto it = mills.find(id);
    if (it != mills.end()) return &it->second;
    if (id.empty() || mills.size() >= limits.mills) {
      ++counters.ignored;
      return nullptr;
    }
    Mill& m = mills[id];
    m.id = id;
    JsonWriter w;
    w.begin_object().field("machine_id", id).end_object();
    events.push_back(make_event(EventKind::kMill, id, w.str()));
    return &m;
  }

  std::string render_situation(const Mill& m) const {
    const SituationRaw& s = *m.situation;
    JsonWriter w;
    w.begin_object()
        .field("machine_id", m.id)
        .field("t", seconds(s.machine_time_ns))
        .field("machine_time_ns", std::to_string(s.machine_time_ns))
        .field("sequence_number", s.sequence_number);
    w.key("step_indices").begin_array();
    for (unsigned i = 0; i < 64; ++i) {
      if ((s.active_steps >> i) & 1U) w.value(i);
    }
    w.end_array();
    w.key("active_steps");
    if (m.has_grafcet && m.grafcet.ok) {
      w.begin_array();
      for (const auto n : active_step_numbers(m.grafcet, s.active_steps)) w.value(n);
      w.end_array();
    } else {
      w.null();
    }
    w.field("modules", module_letters(s.modules_active))
        .field("modules_mask", s.modules_active)
        .field("feed_hold", ((s.modules_active >> 2) & 1U) != 0);  // module C
    w.key("inputs").begin_object();
    for (unsigned i = 0; i < 5; ++i) {
      const bool on = ((s.inputs >> i) & 1U) != 0;
      if (m.has_grafcet && i < m.grafcet.input_names.size()) {
        w.field(m.grafcet.input_names[i], on);
      } else {
        w.field(std::string(1, static_cast<char>('a' + i)), on);
      }
    }
    w.end_object();
    w.field("inputs_mask", s.inputs)
        .field("config_id", s.config_id)
        .field("src_unix_ms", unix_ms(s.src_unix_ns))
        .end_object();
    return w.take();
  }

  std::string render_status(const Mill& m, const smc_data_EdgeStatus* s) const {
    // Re-rendering on liveliness loss keeps the last fields, flips "online".
    if (s == nullptr) {
      std::string j = m.status_json;
      const std::string on = "\"online\":true";
      const auto pos = j.find(on);
      if (pos != std::string::npos) j.replace(pos, on.size(), "\"online\":false");
      return j;
    }
    JsonWriter w;
    w.begin_object()
        .field("machine_id", m.id)
        .field("online", true)
        .field("t", seconds(s->machine_time_ns))
        .field("state", wire::edge_state_name(static_cast<int>(s->state)))
        .field("config_id", get_string(s->config_id))
        .field("job_id", get_string(s->job_id))
        .field("loop_overruns", s->loop_overruns)
        .field("loop_latency_p99_us", s->loop_latency_p99_us)
        .field("message", get_string(s->message))
        .end_object();
    return w.take();
  }

  void write_mill(JsonWriter& w, const Mill& m, bool detail) const {
    w.begin_object().field("machine_id", m.id).field("online", m.online);
    raw_or_null(w, "status", m.status_json);
    raw_or_null(w, "summary", m.summary_json);
    raw_or_null(w, "situation", m.situation_json);
    raw_or_null(w, "config", m.config_brief_json);
    raw_or_null(w, "program", m.program_json);
    w.field("chatter_events", m.chatter_total);
    w.key("job");
    const Job* job = nullptr;
    if (!m.job_id.empty()) {
      auto it = jobs.find(m.job_id);
      if (it != jobs.end()) job = &it->second;
    }
    if (job != nullptr) {
      write_job(w, m.job_id, *job);
    } else {
      w.null();
    }
    if (detail) {
      w.key("chatter");
      write_string_array(w, m.chatter, 50);
      w.key("jobs");
      write_jobs(w, m.id);
    }
    w.end_object();
  }

  void write_job(JsonWriter& w, const std::string& id, const Job& j) const {
    w.begin_object().field("job_id", id).field("machine_id", j.machine_id);
    raw_or_null(w, "status", j.status_doc);
    raw_or_null(w, "progress", j.progress_json);
    w.end_object();
  }

  void write_jobs(JsonWriter& w, const std::string& machine_id) const {
    std::vector<std::pair<std::uint64_t, const std::string*>> order;
    for (const auto& [id, j] : jobs) {
      if (machine_id.empty() || j.machine_id == machine_id) order.emplace_back(j.order, &id);
    }
    std::sort(order.begin(), order.end());
    w.begin_array();
    for (const auto& [o, id] : order) write_job(w, *id, jobs.at(*id));
    w.end_array();
  }

  Job& job(const std::string& id) {
    auto it = jobs.find(id);
    if (it != jobs.end()) return it->second;
    Job& j = jobs[id];
    j.order = ++job_order;
    while (jobs.size() > limits.jobs) evict_job(id);
    return j;
  }

  // Forgets the oldest finished job (else the oldest), never `keep`.
  void evict_job(const std::string& keep) {
    auto victim = jobs.end();
    for (auto it = jobs.begin(); it != jobs.end(); ++it) {
      if (it->first == keep) continue;
      if (victim == jobs.end() || (it->second.finished && !victim->second.finished) ||
          (it->second.finished == victim->second.finished &&
           it->second.order < victim->second.order)) {
        victim = it;
      }
    }
    if (victim != jobs.end()) jobs.erase(victim);
  }

  Event job_event(const std::string& id, const Job& j) const {
    JsonWriter w;
    write_job(w, id, j);
    return make_event(EventKind::kJob, j.machine_id, w.str());
  }
};

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
  const std::size_t n = std::min<std::size_t>(b.count, 128);
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
      .field("part_id", c.program().part_id())
      .field("passes", c.program().passes_size());
  w.key("grafcet").raw(view.json).end_object();
  std::string doc = documents::to_json(c, false);
  std::lock_guard lock(impl_->mu);
  Mill* m = impl_->mill(machine_id, events);
  if (m == nullptr) return events;
  ++impl_->counters.samples;
  m->grafcet = std::move(view);
  m->has_grafcet = true;
  m->config_brief_json = w.take();
  m->config_doc_json = std::move(doc);
  events.push_back(make_event(EventKind::kConfig, machine_id, m->config_brief_json));
  if (m->situation) {  // step numbers and input names may have changed
    m->situation_json = impl_->render_situation(*m);
    events.push_back(make_event(EventKind::kSituation, machine_id, m->situation_json));
  }
  return events;
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

std::vector<Event> CellState::on_command(const CommandRecord& record) {
  std::vector<Event> events;
  std::string json = to_json(record);
  std::lock_guard lock(impl_->mu);
  push_bounded(impl_->commands, json, impl_->limits.commands);
  events.push_back(make_event(EventKind::kCommand, record.request.machine_id, json));
  return events;
}

bool CellState::has_mill(const std::string& machine_id) const {
  std::lock_guard lock(impl_->mu);
  return impl_->mills.count(machine_id) != 0;
}

std::vector<std::string> CellState::mill_ids() const {
  std::lock_guard lock(impl_->mu);
  std::vector<std::string> out;
  for (const auto& [id, m] : impl_->mills) out.push_back(id);
  return out;
}

std::string CellState::mills_json() const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  w.begin_array();
  for (const auto& [id, m] : impl_->mills) impl_->write_mill(w, m, false);
  w.end_array();
  return w.take();
}

std::optional<std::string> CellState::mill_json(const std::string& machine_id) const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  auto it = impl_->mills.find(machine_id);
  if (it == impl_->mills.end()) return std::nullopt;
  impl_->write_mill(w, it->second, true);
  return w.take();
}

std::optional<std::string> CellState::history_json(const std::string& machine_id,
                                                   double window_s) const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  auto it = impl_->mills.find(machine_id);
  if (it == impl_->mills.end()) return std::nullopt;
  const Mill& m = it->second;
  const double last = m.history.empty() ? 0.0 : m.history.back().t;
  const double from = last - window_s;
  auto first = std::find_if(m.history.begin(), m.history.end(),
                            [&](const SummaryPoint& p) { return p.t >= from; });
  auto column = [&](std::string_view key, auto get) {
    w.key(key).begin_array();
    for (auto p = first; p != m.history.end(); ++p) w.value(get(*p));
    w.end_array();
  };
  w.begin_object().field("machine_id", machine_id).field("window_s", window_s);
  column("t", [](const SummaryPoint& p) { return p.t; });
  column("f_y_peak_n", [](const SummaryPoint& p) { return p.f_y; });
  column("f_ref_n", [](const SummaryPoint& p) { return p.f_ref; });
  column("feedrate_mm_s", [](const SummaryPoint& p) { return p.feed; });
  column("pass_index", [](const SummaryPoint& p) { return p.pass_index; });
  column("pass_count", [](const SummaryPoint& p) { return p.pass_count; });
  column("in_contact", [](const SummaryPoint& p) { return p.contact; });
  column("chatter", [](const SummaryPoint& p) { return p.chatter; });
  // Situations from the last one before the window (the state the window
  // opens in) to now, for the feed-hold and suppression marks.
  w.key("situations").begin_array();
  auto s = std::find_if(m.situations.begin(), m.situations.end(),
                        [&](const SituationPoint& p) { return p.t >= from; });
  if (s != m.situations.begin()) --s;
  for (; s != m.situations.end(); ++s) {
    w.begin_object()
        .field("t", s->t)
        .field("modules", module_letters(s->modules))
        .field("modules_mask", s->modules);
    w.key("step_indices").begin_array();
    for (unsigned i = 0; i < 64; ++i) {
      if ((s->steps >> i) & 1U) w.value(i);
    }
    w.end_array().end_object();
  }
  w.end_array();
  w.key("chatter_events");
  write_string_array(w, m.chatter, m.chatter.size());
  w.key("batches");
  write_string_array(w, m.batches, m.batches.size());
  w.end_object();
  return w.take();
}

std::optional<std::string> CellState::config_json(const std::string& machine_id) const {
  std::lock_guard lock(impl_->mu);
  auto it = impl_->mills.find(machine_id);
  if (it == impl_->mills.end()) return std::nullopt;
  return it->second.config_doc_json.empty() ? std::string("null") : it->second.config_doc_json;
}

std::optional<std::string> CellState::grafcet_json(const std::string& machine_id) const {
  std::lock_guard lock(impl_->mu);
  auto it = impl_->mills.find(machine_id);
  if (it == impl_->mills.end()) return std::nullopt;
  return it->second.has_grafcet ? it->second.grafcet.json : std::string("null");
}

std::string CellState::jobs_json(const std::string& machine_id) const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  impl_->write_jobs(w, machine_id);
  return w.take();
}

std::string CellState::chatter_json(const std::string& machine_id) const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  w.begin_array();
  for (const auto& [id, m] : impl_->mills) {
    if (!machine_id.empty() && id != machine_id) continue;
    for (const auto& e : m.chatter) w.raw(e);
  }
  w.end_array();
  return w.take();
}

std::string CellState::commands_json() const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  write_string_array(w, impl_->commands, impl_->commands.size());
  return w.take();
}

std::string CellState::cell_json() const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  w.begin_object().key("mills").begin_array();
  for (const auto& [id, m] : impl_->mills) impl_->write_mill(w, m, false);
  w.end_array().key("jobs");
  impl_->write_jobs(w, {});
  w.key("commands");
  write_string_array(w, impl_->commands, 50);
  w.end_object();
  return w.take();
}

CellState::Counters CellState::counters() const {
  std::lock_guard lock(impl_->mu);
  return impl_->counters;
}

}  // namespace smc::dashboard
