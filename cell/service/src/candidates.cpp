#include "smc/cell/candidates.hpp"

#include <cmath>
#include <stdexcept>

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

}  // namespace smc::cell
