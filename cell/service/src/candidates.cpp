#include "smc/cell/candidates.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace smc::cell {

std::vector<MachineModels> machine_candidates(
    store::Store& db, const store::Job& job, const store::Part& part,
    const std::function<bool(const std::string&)>& available) {
  std::vector<MachineModels> out;
  const auto bounds = stability_bounds(db.stability_evidence(part.id));
  for (auto& m : db.machines()) {
    if (m.retired_at_ms != 0) continue;
    if (!job.spec.machine_id().empty() && m.id != job.spec.machine_id()) continue;
    MachineModels c;
    c.available = !available || available(m.id);
    c.models = db.find_models(m.id, job.spec.tool_id(), part.material_id, part.id);
    for (const auto& b : bounds) {
      if (b.machine_id == m.id && b.tool_id == job.spec.tool_id() &&
          b.rpm == std::lround(job.spec.spindle_rpm()))
        c.bound = b;
    }
    c.machine = std::move(m);
    out.push_back(std::move(c));
  }
  return out;
}

PlanInputs bind_job(store::Store& db, const store::Job& job, Selection& selection,
                    const std::function<bool(const std::string&)>& available) {
  const auto part = db.part(job.spec.part_id());
  if (!part)
    throw std::runtime_error("job " + job.id + ": unknown part '" + job.spec.part_id() + "'");
  const auto tool = db.tool(job.spec.tool_id());
  if (!tool)
    throw std::runtime_error("job " + job.id + ": unknown tool '" + job.spec.tool_id() + "'");
  if (tool->retired_at_ms != 0) {
    // Retired after the job was accepted: broken (module N) or withdrawn.
    throw std::runtime_error("job " + job.id + ": tool '" + tool->id +
                             "' was retired after the job was submitted (`smc-cell catalog show "
                             "tool " +
                             tool->id +
                             "` says why); submit it again with another "
                             "tool");
  }
  if (!job.spec.machine_id().empty()) {
    const auto m = db.machine(job.spec.machine_id());
    if (m && m->retired_at_ms != 0) {
      throw std::runtime_error("job " + job.id + ": machine '" + m->id +
                               "' was retired after the job was submitted; submit it again "
                               "for another machine");
    }
  }
  PlanInputs in{job, *part, *tool, {}, {}};
  selection = bind_and_select(in, machine_candidates(db, job, *part, available));
  return in;
}

std::optional<store::ProcessModel> structure_model(store::Store& db, const store::Job& job,
                                                   const std::string& machine_id) {
  if (machine_id.empty()) return std::nullopt;
  const auto part = db.part(job.spec.part_id());
  const std::string material = part ? part->material_id : job.spec.material();
  std::vector<store::ProcessModel> found;
  for (auto& m : db.find_models(machine_id, job.spec.tool_id(), "", "")) {
    if (m.kind != store::ModelKind::kMilling) continue;
    const auto& st = m.milling.structure();
    if (st.tool_y_size() + st.part_y_size() == 0) continue;  // nothing for E in y
    found.push_back(std::move(m));
  }
  // find_models' order within each rank (stable).
  const auto rank = [&](const store::ProcessModel& m) {
    return std::make_tuple(!m.suspect_reason.empty(), m.part_id != job.spec.part_id(),
                           m.material_id != material);
  };
  std::stable_sort(found.begin(), found.end(),
                   [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
  if (found.empty()) return std::nullopt;
  return std::move(found.front());
}

}  // namespace smc::cell
