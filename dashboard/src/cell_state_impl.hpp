#pragma once
// CellState's insides, shared by its two halves: recording (cell_state.cpp,
// the DDS thread) and rendering the REST API's JSON (cell_state_json.cpp,
// any thread). Private to the dashboard library.

#include <algorithm>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cell_state.hpp"
#include "grafcet_view.hpp"
#include "json.hpp"
#include "smc/documents/load.hpp"
#include "smc/supervision/modules.hpp"
#include "smc/wire/limits.hpp"
#include "smc/wire/names.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::dashboard {

namespace cell_detail {

using wire::get_string;

constexpr std::uint64_t kMaxExactJs = std::uint64_t{1} << 53;

inline double seconds(std::uint64_t ns) { return static_cast<double>(ns) * 1e-9; }
inline double unix_ms(std::int64_t ns) { return static_cast<double>(ns) * 1e-6; }

// A 64-bit id as a JSON number when a browser holds it exactly, else a string.
inline void write_id(JsonWriter& w, std::string_view key, std::uint64_t v) {
  w.key(key);
  if (v < kMaxExactJs) {
    w.value(v);
  } else {
    w.value(std::to_string(v));
  }
}

inline std::string module_letters(std::uint32_t mask) {
  return supervision::letters(static_cast<supervision::ModuleMask>(mask));
}

template <class T>
inline void push_bounded(std::deque<T>& d, T v, std::size_t cap) {
  d.push_back(std::move(v));
  while (d.size() > cap) d.pop_front();
}

inline void write_string_array(JsonWriter& w, const std::deque<std::string>& items,
                               std::size_t last_n) {
  w.begin_array();
  const std::size_t start = items.size() > last_n ? items.size() - last_n : 0;
  for (std::size_t i = start; i < items.size(); ++i) w.raw(items[i]);
  w.end_array();
}

inline void raw_or_null(JsonWriter& w, std::string_view key, const std::string& json) {
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
  float power = 0;  // mean spindle power over the revolution
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

}  // namespace cell_detail

using namespace cell_detail;

struct CellState::Mill {
  std::string id;
  bool online = false;
  std::string status_json;
  std::string summary_json;
  std::string situation_json;
  std::optional<SituationRaw> situation;
  std::string program_json;
  // The configuration in force: the one the edge's status names, never
  // merely the last one the cell published (the edge may have refused it).
  std::string config_brief_json;  // with the Grafcet model
  std::string config_doc_json;    // the whole SupervisorConfig (Protobuf JSON mapping)
  std::string config_in_force;    // its id (adopted)
  std::string reported_config;    // the id the edge's status names
  // Configurations published for this mill, by id, until the edge reports
  // one in force (kept: the last few).
  struct Candidate {
    GrafcetView grafcet;
    std::string brief_json;
    std::string doc_json;
    std::uint64_t order = 0;
  };
  std::map<std::string, Candidate> candidates;
  std::uint64_t candidate_order = 0;
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
  std::string catalog;  // the latest CatalogView (Protobuf JSON mapping); empty: none yet
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
        .field("refused_config_id", get_string(s->refused_config_id))
        .field("refusal", get_string(s->refusal))
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

}  // namespace smc::dashboard
