#pragma once
// Typed writers and readers. Move-only; destructors never throw.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "smc/transport/entity.hpp"
#include "smc/transport/qos.hpp"
#include "smc/transport/topic.hpp"

namespace smc::transport {

enum class InstanceState : uint8_t { kAlive, kDisposed, kNoWriters };

struct SampleInfo {
  bool valid_data = false;  // false: an instance-state change only
  InstanceState instance_state = InstanceState::kAlive;
  int64_t source_timestamp_ns = 0;
  uint64_t publication_handle = 0;
};

struct MatchStatus {
  uint32_t current_count = 0;
  uint32_t total_count = 0;
};

struct LivelinessStatus {
  uint32_t alive_count = 0;
  uint32_t not_alive_count = 0;
};

class WriterBase {
 public:
  WriterBase(TopicBase& topic, const QosProfile& qos);
  // A writer into machine `machine`'s partition (Participant::publisher_for).
  WriterBase(TopicBase& topic, const QosProfile& qos, const std::string& machine);
  EntityHandle handle() const noexcept { return entity_.handle(); }
  void write_raw(const void* sample);
  void dispose_raw(const void* sample);
  void unregister_raw(const void* sample);
  MatchStatus publication_matched() const;
  void assert_liveliness();
  // Blocks until at least `n` readers match or the timeout passes.
  bool wait_for_readers(uint32_t n, std::chrono::nanoseconds timeout) const;

 private:
  Entity entity_;
};

template <class T>
class Writer : public WriterBase {
 public:
  explicit Writer(Topic<T>& topic) : WriterBase(topic, topic.qos()) {}
  Writer(Topic<T>& topic, const QosProfile& qos) : WriterBase(topic, qos) {}
  Writer(Topic<T>& topic, const std::string& machine) : WriterBase(topic, topic.qos(), machine) {}
  void write(const T& sample) { write_raw(&sample); }
  void dispose(const T& key) { dispose_raw(&key); }
  void unregister(const T& key) { unregister_raw(&key); }
};

// What a reader does with a sample that a writer in one machine's partition
// wrote about another machine (see ReaderBase): `what` names the topic, the
// writer's machine and the sample's. The default writes a line to stderr.
// Any thread; set it once at start-up.
using RefusalHandler = void (*)(const std::string& what);
void set_refusal_handler(RefusalHandler handler) noexcept;

class ReaderBase {
 public:
  using RawVisitor = std::function<void(const void* sample, const SampleInfo& info)>;
  // The machine a sample is about (its key), for the origin check; null: the
  // type is not keyed by machine.
  using MachineOf = const char* (*)(const void* sample);
  ReaderBase(TopicBase& topic, const QosProfile& qos, MachineOf machine_of = nullptr);
  ~ReaderBase();
  ReaderBase(ReaderBase&&) noexcept;
  // Not assignable: the reader's listener holds its origins until the
  // reader is deleted.
  ReaderBase& operator=(ReaderBase&&) = delete;
  EntityHandle handle() const noexcept { return entity_.handle(); }
  // Takes up to `max` samples (loaned, no copy) and visits each; returns the
  // number taken. The sample pointer is valid only during the visit.
  size_t take_raw(const RawVisitor& visit, size_t max = 64);
  // As take_raw but leaves the samples in the reader (marked read).
  size_t read_raw(const RawVisitor& visit, size_t max = 64);
  MatchStatus subscription_matched() const;
  LivelinessStatus liveliness() const;
  bool wait_for_writers(uint32_t n, std::chrono::nanoseconds timeout) const;
  // Samples dropped by the origin check: a writer in machine X's partition
  // (which DDS Security grants to X's certificate alone) wrote about machine
  // Y. Writers in the cell's partition are not checked.
  uint64_t refused() const noexcept { return refused_; }

  // The machine whose partition each writer publishes in ("" for the
  // cell's partition), recorded when it matches (a listener), so that its
  // samples are judged by it even when taken after the writer has gone.
  struct Origins;

 private:
  size_t collect(const RawVisitor& visit, size_t max, bool take);
  std::unique_ptr<Origins> origins_;  // before entity_: outlives the reader's listener
  Entity entity_;
  std::string topic_;
  MachineOf machine_of_ = nullptr;
  uint64_t refused_ = 0;
};

namespace detail {
template <class T>
const char* machine_key(const void* sample) {
  if constexpr (requires(const T& t) { t.machine_id; }) {
    return static_cast<const T*>(sample)->machine_id;
  } else {
    return static_cast<const T*>(sample)->key;
  }
}
template <class T>
constexpr ReaderBase::MachineOf machine_of() {
  if constexpr (
      requires(const T& t) { t.machine_id; } || requires(const T& t) { t.key; }) {
    return &machine_key<T>;
  } else {
    return nullptr;
  }
}
}  // namespace detail

template <class T>
class Reader : public ReaderBase {
 public:
  explicit Reader(Topic<T>& topic) : ReaderBase(topic, topic.qos(), detail::machine_of<T>()) {}
  Reader(Topic<T>& topic, const QosProfile& qos)
      : ReaderBase(topic, qos, detail::machine_of<T>()) {}

  // visit(const T&, const SampleInfo&) for every sample taken, valid or not.
  template <class F>
  size_t take(F&& visit, size_t max = 64) {
    return take_raw(
        [&](const void* s, const SampleInfo& i) { visit(*static_cast<const T*>(s), i); }, max);
  }
  template <class F>
  size_t read(F&& visit, size_t max = 64) {
    return read_raw(
        [&](const void* s, const SampleInfo& i) { visit(*static_cast<const T*>(s), i); }, max);
  }
  // Takes the next valid sample as a copy. Only for types without sequences
  // or unbounded strings (a shallow copy would alias loaned memory).
  std::optional<T> take_one() {
    std::optional<T> out;
    take_raw(
        [&](const void* s, const SampleInfo& i) {
          if (i.valid_data && !out) out = *static_cast<const T*>(s);
        },
        1);
    return out;
  }
};

// Waits on readers from a thread the caller owns. wake() (any thread) makes
// a pending wait() return early with no reader triggered.
class WaitSet {
 public:
  explicit WaitSet(const Participant& participant);
  // Trigger when `reader` has samples in any state; wait() returns `token`.
  void attach(const ReaderBase& reader, int64_t token);
  // Trigger also on liveliness changes of the reader's matched writers.
  void attach_liveliness(const ReaderBase& reader, int64_t token);
  // Returns the tokens whose conditions triggered (empty on timeout or wake).
  // Fills `out`, which the caller may reuse to avoid allocation.
  void wait(std::chrono::nanoseconds timeout, std::vector<int64_t>& out);
  void wake();

 private:
  Entity waitset_;
  Entity guard_;
  std::vector<Entity> conditions_;
};

}  // namespace smc::transport
