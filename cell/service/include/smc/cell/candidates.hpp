#pragma once
// The machines a job could be planned for, each with the models the cell's
// database holds for it: what bind_and_select (planner.hpp) chooses from.
// Shared by the cell service and `smc-cell plan`.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "smc/cell/planner.hpp"
#include "smc/cell/store/store.hpp"

namespace smc::cell {

// Every machine in the database (only the job's own when it names one), in
// id order, with the models for the job's tool, material and part on it.
// `available` tells whether a machine's edge is seen or not yet given up
// (empty: all are).
std::vector<MachineModels> machine_candidates(
    store::Store& db, const store::Job& job, const store::Part& part,
    const std::function<bool(const std::string&)>& available = {});

// PlanInputs for a stored (or file) job, bound to its machine and selected:
// the part and tool from the database, then bind_and_select over
// machine_candidates. Throws std::runtime_error for an unknown part or tool.
PlanInputs bind_job(store::Store& db, const store::Job& job, Selection& selection,
                    const std::function<bool(const std::string&)>& available = {});

// The model whose structure module E undoes on `machine_id` for `job`
// (the vibration estimate of edge/CHATTER.md: without a structure E judges
// the force spectrum alone): a milling model of that machine with the job's
// tool, not retired; one not suspect first, then one for the job's part,
// then for its material, then find_models' order. None: the cell knows no
// structure of that machine with that tool.
std::optional<store::ProcessModel> structure_model(store::Store& db, const store::Job& job,
                                                   const std::string& machine_id);

}  // namespace smc::cell
