#include "smc/cell/dispatch.hpp"

#include <algorithm>

namespace smc::cell {

std::vector<Assignment> choose_assignments(const std::vector<PlannedJob>& planned,
                                           const std::vector<MillView>& mills,
                                           std::set<std::string> busy) {
  std::vector<const PlannedJob*> order;
  order.reserve(planned.size());
  for (const auto& j : planned) order.push_back(&j);
  std::stable_sort(order.begin(), order.end(), [](const PlannedJob* a, const PlannedJob* b) {
    return a->priority > b->priority;
  });
  std::vector<Assignment> out;
  for (const PlannedJob* j : order) {
    for (const MillView& m : mills) {
      if (busy.count(m.id) || !m.alive || !m.ready) continue;
      if (!j->machine_id.empty() && j->machine_id != m.id) continue;
      out.push_back({j->id, m.id, j->attempt + 1});
      busy.insert(m.id);
      break;
    }
  }
  return out;
}

bool edge_lost_past_grace(bool alive, std::chrono::steady_clock::time_point lost_since,
                          std::chrono::steady_clock::time_point cell_started,
                          std::chrono::steady_clock::time_point now,
                          std::chrono::milliseconds grace) {
  if (alive) return false;
  return now - std::max(lost_since, cell_started) >= grace;
}

AfterInterruption after_interruption(uint32_t attempt, uint32_t max_attempts) {
  if (attempt < max_attempts) {
    return {true, "re-queued after attempt " + std::to_string(attempt) + " of " +
                      std::to_string(max_attempts)};
  }
  return {false, "interrupted on every one of " + std::to_string(max_attempts) + " attempts"};
}

}  // namespace smc::cell
