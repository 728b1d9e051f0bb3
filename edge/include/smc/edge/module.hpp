#pragma once
// The interface of a machining module (A–L). Fits on one screen, in the
// manner of a HAL component: parameters in configure(), state reset in
// reset(), and an update() per period.
//
// Real-time contract: reset(), on_sample() and update() run in the loop.
// They never allocate, lock, log, throw or block. configure() runs before
// the loop starts (or on a configuration swap, off the loop) and may.

#include "smc/edge/parameters.hpp"
#include "smc/edge/signals.hpp"
#include "smc/edge/types.hpp"

namespace smc::edge {

enum class Period : uint8_t {
  kEvent,       // acts when the supervisor activates it (C, D's latch, F, G)
  kFast,        // every fast period (10 ms): A, B, D, G's timer
  kRevolution,  // every slow period (one spindle revolution, 40 ms): E, H, I, J, K, L
};

class Module {
 public:
  explicit Module(ModuleId id) noexcept : id_(id) {}
  virtual ~Module() = default;
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;

  ModuleId id() const noexcept { return id_; }
  virtual Period period() const noexcept = 0;

  // Not real-time: read parameters, size buffers. Throws ConfigError.
  virtual void configure(const EdgeParameters& params) = 0;
  // Real-time: back to the initial state (the impulse action "X*").
  virtual void reset() noexcept = 0;
  // Real-time: clear the signals this module owns (called with reset() by
  // the core, so a reset module's old outputs cannot fire a transition).
  virtual void clear_outputs(Signals& /*s*/) noexcept {}
  // Real-time: every sample while active (accumulators). Default: nothing.
  virtual Status on_sample(Signals& /*s*/) noexcept { return Status::kOk; }
  // Real-time: once per period() while active.
  virtual Status update(Signals& s) noexcept = 0;

 private:
  ModuleId id_;
};

}  // namespace smc::edge
