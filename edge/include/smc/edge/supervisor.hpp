#pragma once
// The state supervisor (receptivities a–h from module outputs and operator
// inputs) and the operation supervisor (the configured Grafcet, whose level
// actions enable modules and whose impulse actions reset them).

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "smc/edge/signals.hpp"
#include "smc/edge/types.hpp"

namespace smc::edge {

// What the operation supervisor decided in one evaluation.
struct Situation {
  uint64_t active_steps = 0;  // bit i: the Grafcet's step with index i
  ModuleMask active = 0;      // level actions: modules enabled
  ModuleMask impulses = 0;    // impulse actions fired: modules to reset
  uint32_t inputs = 0;        // receptivities a..e as bits 0..4
  bool changed = false;       // the situation changed in this evaluation
  bool error = false;         // no stable situation was reached
};

// State supervisor: the instantaneous operation state as receptivities.
// `fault_hold` forces a (the machine holds its feed as if the operator had
// asked). Real-time safe.
uint32_t receptivities(const Signals& s, bool fault_hold) noexcept;

class OperationSupervisor {
 public:
  // Not real-time. Runs a Grafcet already parsed, bound and verified
  // (supervision::bind_grafcet, as a validated configuration carries it):
  // level actions named by module letters enable modules, impulse actions
  // "X*" reset them.
  explicit OperationSupervisor(const supervision::BoundGrafcet& grafcet);
  // Not real-time. Binds `grafcet_text` first: any action that is not a
  // module in `allowed`, an input other than a–h, a parse error or a failed
  // verification throws ConfigError naming the file position or the check.
  OperationSupervisor(std::string_view grafcet_text, std::string_view source_name,
                      ModuleMask allowed);
  ~OperationSupervisor();
  OperationSupervisor(const OperationSupervisor&) = delete;
  OperationSupervisor& operator=(const OperationSupervisor&) = delete;

  // Real-time: back to the initial situation; the next evaluate() reports
  // the initial steps' impulse actions.
  void reset() noexcept;
  // Real-time: one evolution to a stable situation under `inputs`.
  const Situation& evaluate(uint32_t inputs) noexcept;
  const Situation& situation() const noexcept { return situation_; }

  // Not real-time: the Grafcet's step numbers by index, and its name.
  int step_number(int index) const;
  int step_count() const;
  const std::string& name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Situation situation_;
};

}  // namespace smc::edge
