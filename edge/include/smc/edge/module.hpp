#pragma once
// The interface of a supervisory module (A–L, and any later one). Fits on
// one screen, in the manner of a HAL component: it declares when it runs and
// which signals it writes, reads its parameters in configure(), resets in
// reset(), and does its work in update() once per period.
//
// Real-time contract: reset(), clear_outputs(), on_sample(), requested() and
// update() run in the loop. They never allocate, lock, log, throw or block.
// The declarations, configure() and attach() run before the loop starts (or
// on a configuration swap, off the loop); configure() may allocate.
//
// The core schedules modules from their declarations alone: every sample
// for takes_samples(), every period() (fast or revolution) while active, an
// event module when requested(), and after the operation supervisor for
// after_supervisor() — in the registry's data-flow order
// (edge/src/modules/registry.cpp).

#include "smc/edge/parameters.hpp"
#include "smc/edge/program.hpp"
#include "smc/edge/signals.hpp"
#include "smc/edge/types.hpp"

namespace smc::edge {

enum class Period : uint8_t {
  kEvent,       // runs when requested() (F), or not at all: its activity is its action (C)
  kFast,        // every fast period (10 ms): A, B, D, G
  kRevolution,  // every slow period (one spindle revolution, 40 ms): E, H, I, J, K, L
};

class Module {
 public:
  explicit Module(ModuleId id) noexcept : id_(id) {}
  virtual ~Module() = default;
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;

  ModuleId id() const noexcept { return id_; }

  // ---- declarations (constant for a module's life)
  virtual Period period() const noexcept = 0;
  // The output groups this module writes (signals.hpp); each has one owner.
  virtual SignalMask writes() const noexcept = 0;
  // on_sample() is called every sample while active.
  virtual bool takes_samples() const noexcept { return false; }
  // Runs after the operation supervisor in the same tick, because it acts on
  // this tick's module activity (A: a hold must act at once).
  virtual bool after_supervisor() const noexcept { return false; }
  // Its output is due in the tick it becomes active or is reset, not only at
  // its next period: the core runs update() once then, after the operation
  // supervisor and before the after_supervisor() modules (K, L: the feed to
  // start from, so that A never falls back to the programmed feed).
  virtual bool starts_on_activation() const noexcept { return false; }
  // A routine that starts afresh whenever it becomes active, as if its
  // Grafcet step also reset it (G, O): the core resets it on activation.
  virtual bool resets_on_activation() const noexcept { return false; }
  // Runs under the state supervisor whenever it is configured (M), not as an
  // action of the operation supervisor: the Grafcet neither names nor
  // switches it.
  virtual bool supervisory() const noexcept { return false; }

  // ---- set-up, not real-time
  // Read parameters, size buffers. Throws ConfigError.
  virtual void configure(const EdgeParameters& params) = 0;
  // The program in execution, for a module that rewrites it (F). Default: none.
  virtual void attach(RunningProgram& /*program*/) noexcept {}

  // ---- real-time
  // Back to the initial state (the impulse action "X*").
  virtual void reset() noexcept = 0;
  // Clear the signals this module owns (called with reset() by the core, so
  // a reset module's old outputs cannot fire a transition).
  virtual void clear_outputs(Signals& /*s*/) noexcept {}
  // Every sample while active, when takes_samples(). Default: nothing.
  virtual Status on_sample(Signals& /*s*/) noexcept { return Status::kOk; }
  // An event module: has another module asked for it this fast period?
  virtual bool requested(const Signals& /*s*/) const noexcept { return false; }
  // Once per period() while active (or when requested(), for kEvent).
  virtual Status update(Signals& s) noexcept = 0;

  // Why the last kError was returned: text naming the cause and, where
  // there is one, the field that fixes it (the fault hold's reason).
  // nullptr: none given.
  const char* error_reason() const noexcept { return error_; }

 protected:
  // Returns kError, keeping `why`: a string literal, or a buffer of the
  // module's own that it writes once and leaves unchanged until it is
  // configured again (the fault event carries the pointer to another
  // thread). Nothing is allocated.
  Status fail(const char* why) noexcept {
    error_ = why;
    return Status::kError;
  }

 private:
  ModuleId id_;
  const char* error_ = nullptr;
};

}  // namespace smc::edge
