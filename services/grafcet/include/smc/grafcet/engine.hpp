#pragma once
// The evolution engine: runs one Grafcet with IEC 60848 evolution rules, for
// the edge's 2 kHz real-time loop.
//
//   Engine engine(grafcet);                        // set-up: allocates
//   const int a = engine.input_index("a");         // set-up: resolve names once
//   const int L = engine.action_index("L");
//   ...
//   const Evaluation& r = engine.evaluate(inputs); // loop: real-time safe
//   if (r.impulse_actions >> L & 1) reset_module_L();
//   module_L_active = r.level_actions >> L & 1;
//
// Real-time safe (no allocation, no lock, no exception, bounded time):
// evaluate(), reset(), last() and every const accessor taking an index.
// The name lookups are meant for set-up but do not allocate either.
//
// Semantics (README.md, "Evolution"): one evaluate() call is one external
// event. Enabled transitions (all preceding steps active) whose receptivity
// is true are firable; all firable transitions fire together, except that
// where a checking order is declared for a step, only the first firable
// transition in that order leaving the step fires; a step both deactivated
// and activated stays active. Rounds repeat with the same inputs (edges of
// inputs are seen by the first round only) until no transition is firable
// or a round leaves the situation unchanged. If that takes more than
// `max_rounds` rounds the evaluation stops there and reports `unstable`.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "smc/grafcet/types.hpp"

namespace smc::grafcet {

inline constexpr std::uint32_t kDefaultMaxRounds = 128;

struct EngineOptions {
  // Most rounds of transient evolution in one evaluation. The verifier
  // checks the Grafcet needs no more (VerifyOptions::max_rounds).
  std::uint32_t max_rounds = kDefaultMaxRounds;
};

struct Evaluation {
  Mask active_steps = 0;     // stable situation reached; bit i = step index i
  Mask level_actions = 0;    // level actions of the active steps; bit = action index
  Mask impulse_actions = 0;  // impulse actions fired in this evaluation (each once)
  Mask activated_steps = 0;  // steps that became active in this evaluation,
                             // transient ones included
  std::uint32_t rounds = 0;  // rounds of firing in this evaluation (0: none)
  bool changed = false;      // active_steps differs from the previous result
                             // (always true for the first evaluation after reset)
  bool unstable = false;     // max_rounds exhausted: an unstable cycle; the
                             // situation is where the evolution was stopped
};

// One engine per loop (not thread-safe). A moved-from engine may only be
// destroyed or assigned to.
class Engine {
 public:
  // Copies what it needs: the Grafcet may be destroyed afterwards.
  explicit Engine(const Grafcet& grafcet, EngineOptions options = {});
  ~Engine();
  Engine(Engine&&) noexcept;
  Engine& operator=(Engine&&) noexcept;
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // ---- set-up -----------------------------------------------------------
  // -1 when the name or number is unknown.
  int input_index(std::string_view name) const noexcept;
  int action_index(std::string_view name) const noexcept;
  int step_index(std::uint32_t number) const noexcept;

  std::size_t num_inputs() const noexcept;
  std::size_t num_actions() const noexcept;
  std::size_t num_steps() const noexcept;
  // Index -> designer's step number / names; 0 or "" for an invalid index.
  std::uint32_t step_number(std::size_t index) const noexcept;
  std::string_view input_name(std::size_t index) const noexcept;
  std::string_view action_name(std::size_t index) const noexcept;
  Mask initial_steps() const noexcept;

  // ---- real-time loop -----------------------------------------------------
  // One external event: bit i of `inputs` = input i (bits beyond the
  // declared inputs are ignored). Rising and falling edges are taken against
  // the previous call's inputs. The reference stays valid until the next
  // call on this engine.
  const Evaluation& evaluate(std::uint64_t inputs) noexcept;

  // Back to the initial situation. Nothing fires in reset() itself: the next
  // evaluate() starts from the initial situation, reports the impulse actions
  // of the initial steps as fired (step 1's E*, K*, L* exactly once), sees no
  // input edges, then evolves with its inputs. A new engine starts the same way.
  void reset() noexcept;

  // The last result (the initial situation, nothing fired, after reset).
  const Evaluation& last() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::grafcet
