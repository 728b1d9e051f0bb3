#pragma once
// Exhaustive verification of a Grafcet: every situation reachable from the
// initial one under every valuation of the inputs, evolved exactly as the
// Engine does. Checks (definitions in README.md, "Verifier"): unreachable
// steps, unresolved conflicts, deadlocks, transient cycles, transient
// evolutions longer than the engine's bound, and the file's invariants. Each
// violation that happens on the way carries a shortest input sequence from
// the initial situation. Offline only (allocates).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "smc/grafcet/engine.hpp"
#include "smc/grafcet/model.hpp"

namespace smc::grafcet {

enum class Check : std::uint8_t {
  kUnreachableStep,  // a step never active, not even transiently
  kConflict,         // two transitions sharing a preceding step fire together
  kDeadlock,         // a reachable stable situation no input valuation leaves
  kTransientCycle,   // transient evolution that never reaches stability
  kRoundBound,       // transient evolution longer than max_rounds
  kInvariant,        // a user invariant is false
  kLimit,            // too big to explore exhaustively
};
const char* check_name(Check check) noexcept;

// One evaluation on a counterexample path.
struct PathStep {
  Mask inputs = 0;    // input valuation given to evaluate()
  Mask steps = 0;     // stable situation reached (if !stable: where it stopped)
  Mask impulses = 0;  // impulse actions fired
  bool stable = true;
};

struct Violation {
  Check check = Check::kInvariant;
  std::string subject;         // "step 6", "transitions (2) and (3) at step 2", "invariant \"..\""
  std::string detail;          // what exactly, in words
  SourceLocation where;        // of the step / transition / invariant concerned
  std::vector<PathStep> path;  // from the initial situation; empty if none applies
};

struct InvariantResult {
  std::string name;
  SourceLocation where;
  bool held = true;
  std::size_t evaluations = 0;  // evolutions it was evaluated on
};

struct VerifyOptions {
  std::uint32_t max_rounds = kDefaultMaxRounds;  // the engine's bound to check against
  std::size_t max_inputs = 20;                   // inputs read by the Grafcet, enumerated 2^n
  std::size_t max_states = 1u << 20;             // explored states
  std::size_t max_per_check = 10;                // violations kept per check (the rest counted)
  // Work budget: evolution rounds summed over the exploration (each
  // evolution counts at least one). Deterministic: the same Grafcet and
  // budget give the same verdict on any machine. Exceeding it is a kLimit
  // violation and ends the exploration. 0: no budget.
  std::uint64_t max_work = 0;
  // Wall-clock budget, checked every 256 evolutions; 0: none. A guard for
  // what the work budget does not count (e.g. a slow machine).
  std::chrono::milliseconds max_time{0};
};

struct Report {
  std::vector<Violation> violations;
  std::size_t violations_dropped = 0;       // beyond max_per_check
  std::vector<InvariantResult> invariants;  // one per invariant, file order
  std::vector<std::string> notes;           // non-failing observations
  // Exploration figures.
  std::size_t states = 0;               // (situation, previous edge inputs) pairs
  std::size_t evolutions = 0;           // states x valuations evolved
  std::size_t valuations = 0;           // per state
  std::size_t stable_situations = 0;    // distinct reachable stable situations
  std::uint32_t longest_transient = 0;  // most rounds in one evaluation
  std::uint32_t max_rounds = 0;         // the engine bound checked against
  std::uint64_t work = 0;               // evolution rounds summed (see VerifyOptions::max_work)
  bool complete = true;                 // the exploration was not cut short by a budget
  Mask inputs_read = 0;                 // inputs enumerated
  Mask reachable_steps = 0;
  bool ok() const noexcept { return violations.empty(); }
};

Report verify(const Grafcet& grafcet, const VerifyOptions& options = {});

// The human-readable report `smc-cell grafcet check` prints.
std::string format_report(const Grafcet& grafcet, const Report& report);

}  // namespace smc::grafcet
