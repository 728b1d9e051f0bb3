// CellState, reading: the REST API's JSON documents, from any thread.

#include "cell_state_impl.hpp"

namespace smc::dashboard {

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
  column("spindle_power_w", [](const SummaryPoint& p) { return p.power; });
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

std::string CellState::catalog_json() const {
  JsonWriter w;
  std::lock_guard lock(impl_->mu);
  w.begin_object().key("view");
  if (impl_->catalog.empty()) {
    w.null();
  } else {
    w.raw(impl_->catalog);
  }
  w.key("mills").begin_array();
  for (const auto& [id, m] : impl_->mills) impl_->write_mill(w, m, false);
  w.end_array().end_object();
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
