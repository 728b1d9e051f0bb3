#pragma once
// One DDS service loop for every process: a waitset over the readers it
// serves, one handler per reader, on a thread the caller owns (never a
// listener). Readers are served in priority order on every wake-up, so a
// reader registered kFirst (operator commands) is never queued behind
// another reader's work in the same iteration; periodic work runs after.
//
//   Dispatcher d(participant);
//   d.on(commands, [&] { take_commands(); }, Priority::kFirst);
//   d.on_instances(status_reader, on_status, on_edge_gone);
//   d.every(std::chrono::seconds(1), [&] { publish_status(); });
//   while (!stop) d.run_once(std::chrono::milliseconds(50));
//
// Errors: a handler's exception propagates out of run_once() (the caller's
// boundary policy decides); wake() may be called from any thread.

#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

#include "smc/transport/endpoint.hpp"

namespace smc::transport {

class Dispatcher {
 public:
  enum class Priority : uint8_t { kFirst, kNormal, kLast };

  explicit Dispatcher(const Participant& participant);

  // `serve` takes from `reader` itself (any number of samples).
  void on(ReaderBase& reader, std::function<void()> serve, Priority priority = Priority::kNormal);
  // Samples of live instances go to `on_sample(sample, info)`; an instance
  // that is no longer alive (disposed, or its writers gone: the liveliness
  // lease of a dead process) goes to `on_gone(key_sample, state)` (the
  // sample then carries only the key).
  template <class T, class OnSample, class OnGone>
  void on_instances(Reader<T>& reader, OnSample on_sample, OnGone on_gone,
                    Priority priority = Priority::kNormal) {
    add(
        &reader,
        [&reader, on_sample, on_gone] {
          reader.take([&](const T& s, const SampleInfo& i) {
            if (i.valid_data && i.instance_state == InstanceState::kAlive) {
              on_sample(s, i);
            } else if (i.instance_state != InstanceState::kAlive) {
              on_gone(s, i.instance_state);
            }
          });
        },
        priority);
  }
  // Served like a reader on every wake-up, but never the reason for one:
  // for high-rate data that is fine in batches (e.g. the cell's force
  // summaries, taken whenever something else wakes the loop or the wait
  // times out).
  void poll(std::function<void()> serve, Priority priority = Priority::kNormal);
  // `fn` at most every `period`, after the readers, from run_once().
  void every(std::chrono::nanoseconds period, std::function<void()> fn);

  // Waits up to `timeout` for data (or wake()), then serves every reader in
  // priority order (registration order within a priority), then the
  // periodic work that is due. Returns the number of handlers called.
  size_t run_once(std::chrono::nanoseconds timeout);
  // Any thread: makes a pending run_once() return from its wait early.
  void wake();

 private:
  void add(ReaderBase* reader, std::function<void()> serve, Priority priority);

  struct Handler {
    Priority priority;
    std::function<void()> serve;
  };
  struct Periodic {
    std::chrono::nanoseconds period;
    std::chrono::steady_clock::time_point next;
    std::function<void()> fn;
  };
  WaitSet waitset_;
  std::vector<Handler> handlers_;  // sorted by priority, stable
  std::vector<Periodic> periodic_;
  std::vector<int64_t> fired_;
};

}  // namespace smc::transport
