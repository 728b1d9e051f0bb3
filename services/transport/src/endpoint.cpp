#include "smc/transport/endpoint.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>

#include "qos_apply.hpp"
#include "smc/transport/participant.hpp"

namespace smc::transport {

namespace {

InstanceState to_state(dds_instance_state_t s) {
  switch (s) {
    case DDS_IST_ALIVE:
      return InstanceState::kAlive;
    case DDS_IST_NOT_ALIVE_DISPOSED:
      return InstanceState::kDisposed;
    case DDS_IST_NOT_ALIVE_NO_WRITERS:
      return InstanceState::kNoWriters;
  }
  return InstanceState::kAlive;
}

// Polls `get` until it returns true or the timeout passes. Used only by the
// wait_for_* helpers at set-up, never on a data path.
template <class F>
bool poll_until(std::chrono::nanoseconds timeout, F&& get) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!get()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

void print_refusal(const std::string& what) { std::fprintf(stderr, "%s\n", what.c_str()); }

std::atomic<RefusalHandler> refusal_handler{&print_refusal};

}  // namespace

void set_refusal_handler(RefusalHandler handler) noexcept {
  refusal_handler.store(handler != nullptr ? handler : &print_refusal);
}

WriterBase::WriterBase(TopicBase& topic, const QosProfile& qos, const std::string& machine) {
  detail::Qos q;
  detail::apply(qos, q.get());
  entity_ = Entity(detail::check(dds_create_writer(topic.participant().publisher_for(machine),
                                                   topic.handle(), q.get(), nullptr),
                                 "dds_create_writer", topic.name() + " for " + machine));
}

WriterBase::WriterBase(TopicBase& topic, const QosProfile& qos) {
  detail::Qos q;
  detail::apply(qos, q.get());
  entity_ = Entity(detail::check(
      dds_create_writer(topic.participant().publisher(), topic.handle(), q.get(), nullptr),
      "dds_create_writer", topic.name()));
}

void WriterBase::write_raw(const void* sample) {
  detail::check(dds_write(entity_.handle(), sample), "dds_write");
}

void WriterBase::dispose_raw(const void* sample) {
  detail::check(dds_dispose(entity_.handle(), sample), "dds_dispose");
}

void WriterBase::unregister_raw(const void* sample) {
  detail::check(dds_unregister_instance(entity_.handle(), sample), "dds_unregister_instance");
}

MatchStatus WriterBase::publication_matched() const {
  dds_publication_matched_status_t st{};
  detail::check(dds_get_publication_matched_status(entity_.handle(), &st),
                "dds_get_publication_matched_status");
  return {st.current_count, st.total_count};
}

void WriterBase::assert_liveliness() {
  detail::check(dds_assert_liveliness(entity_.handle()), "dds_assert_liveliness");
}

bool WriterBase::wait_for_readers(uint32_t n, std::chrono::nanoseconds timeout) const {
  return poll_until(timeout, [&] { return publication_matched().current_count >= n; });
}

struct ReaderBase::Origins {
  std::string cell;  // the cell partition
  std::mutex mu;
  std::unordered_map<uint64_t, std::string> by_writer;  // publication handle -> machine

  // Records every writer matched now and not yet known.
  void record_matched(dds_entity_t reader) {
    std::array<dds_instance_handle_t, 64> handles{};
    const dds_return_t n = dds_get_matched_publications(reader, handles.data(), handles.size());
    for (dds_return_t i = 0; i < std::min<dds_return_t>(n, 64); ++i) {
      {
        std::lock_guard lock(mu);
        if (by_writer.count(handles[static_cast<size_t>(i)]) != 0) continue;
      }
      record(reader, handles[static_cast<size_t>(i)]);
    }
  }

  // Looks a matched writer's partition up and records its machine; false
  // when the writer is not matched (any more).
  bool record(dds_entity_t reader, uint64_t handle) {
    dds_builtintopic_endpoint_t* ep = dds_get_matched_publication_data(reader, handle);
    if (ep == nullptr) return false;
    std::string machine;
    uint32_t n = 0;
    char** names = nullptr;
    if (ep->qos != nullptr && dds_qget_partition(ep->qos, &n, &names)) {
      for (uint32_t k = 0; k < n; ++k) {
        std::string m = machine_of_partition(cell, names[k]);
        // In two machines' partitions at once: nobody's.
        if (!m.empty()) machine = machine.empty() ? m : std::string("?");
        dds_free(names[k]);
      }
      dds_free(names);
    }
    dds_builtintopic_free_endpoint(ep);
    std::lock_guard lock(mu);
    // Writers come and go (every edge restart brings new ones): forget them
    // all now and then rather than keep every one ever seen.
    if (by_writer.size() >= 4096) by_writer.clear();
    by_writer.emplace(handle, std::move(machine));
    return true;
  }

  // The machine of a writer, or nullopt for one never seen matched.
  std::optional<std::string> machine_of(dds_entity_t reader, uint64_t handle) {
    for (int attempt = 0; attempt < 2; ++attempt) {
      {
        std::lock_guard lock(mu);
        auto it = by_writer.find(handle);
        if (it != by_writer.end()) return it->second;
      }
      if (attempt == 0 && !record(reader, handle)) break;
    }
    return std::nullopt;
  }
};

namespace {
// A writer matched: its partition is recorded at once, while it can still
// be looked up.
void on_subscription_matched(dds_entity_t reader, const dds_subscription_matched_status_t status,
                             void* arg) {
  if (status.current_count_change > 0) {
    static_cast<ReaderBase::Origins*>(arg)->record_matched(reader);
  }
}
}  // namespace

ReaderBase::ReaderBase(TopicBase& topic, const QosProfile& qos, MachineOf machine_of)
    : topic_(topic.name()), machine_of_(machine_of) {
  detail::Qos q;
  detail::apply(qos, q.get());
  dds_listener_t* listener = nullptr;
  if (machine_of_ != nullptr) {
    origins_ = std::make_unique<Origins>();
    origins_->cell = topic.participant().options().partition;
    listener = dds_create_listener(origins_.get());
    dds_lset_subscription_matched(listener, &on_subscription_matched);
  }
  const dds_entity_t r =
      dds_create_reader(topic.participant().subscriber(), topic.handle(), q.get(), listener);
  if (listener != nullptr) dds_delete_listener(listener);
  entity_ = Entity(detail::check(r, "dds_create_reader", topic.name()));
  // Writers matched while the reader was being made.
  if (origins_) origins_->record_matched(entity_.handle());
}

ReaderBase::~ReaderBase() = default;
ReaderBase::ReaderBase(ReaderBase&&) noexcept = default;

size_t ReaderBase::collect(const RawVisitor& visit, size_t max, bool take) {
  constexpr size_t kChunk = 64;
  std::array<void*, kChunk> buf{};
  std::array<dds_sample_info_t, kChunk> infos{};
  size_t total = 0;
  while (total < max) {
    const size_t want = std::min(kChunk, max - total);
    buf.fill(nullptr);  // null first entry: Cyclone lends its own buffers
    const auto n = take ? dds_take(entity_.handle(), buf.data(), infos.data(), want,
                                   static_cast<uint32_t>(want))
                        : dds_read(entity_.handle(), buf.data(), infos.data(), want,
                                   static_cast<uint32_t>(want));
    detail::check(n, take ? "dds_take" : "dds_read");
    if (n == 0) break;
    const auto count = static_cast<size_t>(n);
    try {
      for (size_t i = 0; i < count; ++i) {
        SampleInfo info;
        info.valid_data = infos[i].valid_data;
        info.instance_state = to_state(infos[i].instance_state);
        info.source_timestamp_ns = infos[i].source_timestamp;
        info.publication_handle = infos[i].publication_handle;
        if (machine_of_ != nullptr && buf[i] != nullptr) {
          // A writer never seen matched has an unknown partition: its data
          // is refused; an instance-state change (no data) passes.
          const std::optional<std::string> origin =
              origins_->machine_of(entity_.handle(), info.publication_handle);
          const char* key = machine_of_(buf[i]);
          const char* about = key != nullptr ? key : "";
          const bool wrong = !origin ? info.valid_data
                                     : !origin->empty() && std::strcmp(origin->c_str(), about) != 0;
          if (wrong) {
            if (refused_++ == 0 || refused_ % 1000 == 0) {
              refusal_handler.load()(
                  "refused on " + topic_ + ": a sample about machine '" + about + "' from " +
                  (!origin ? std::string("a writer never seen matched")
                           : "a writer in machine '" + *origin + "''s partition") +
                  " (" + std::to_string(refused_) + " so far)");
            }
            continue;
          }
        }
        visit(buf[i], info);
      }
    } catch (...) {
      (void)dds_return_loan(entity_.handle(), buf.data(), n);
      throw;
    }
    detail::check(dds_return_loan(entity_.handle(), buf.data(), n), "dds_return_loan");
    total += count;
    if (count < want || !take) break;  // read() marks samples read; one pass is enough
  }
  return total;
}

size_t ReaderBase::take_raw(const RawVisitor& visit, size_t max) {
  return collect(visit, max, true);
}
size_t ReaderBase::read_raw(const RawVisitor& visit, size_t max) {
  return collect(visit, max, false);
}

MatchStatus ReaderBase::subscription_matched() const {
  dds_subscription_matched_status_t st{};
  detail::check(dds_get_subscription_matched_status(entity_.handle(), &st),
                "dds_get_subscription_matched_status");
  return {st.current_count, st.total_count};
}

LivelinessStatus ReaderBase::liveliness() const {
  dds_liveliness_changed_status_t st{};
  detail::check(dds_get_liveliness_changed_status(entity_.handle(), &st),
                "dds_get_liveliness_changed_status");
  return {st.alive_count, st.not_alive_count};
}

bool ReaderBase::wait_for_writers(uint32_t n, std::chrono::nanoseconds timeout) const {
  return poll_until(timeout, [&] { return subscription_matched().current_count >= n; });
}

WaitSet::WaitSet(const Participant& participant) {
  waitset_ = Entity(detail::check(dds_create_waitset(participant.handle()), "dds_create_waitset"));
  guard_ = Entity(
      detail::check(dds_create_guardcondition(participant.handle()), "dds_create_guardcondition"));
  detail::check(dds_waitset_attach(waitset_.handle(), guard_.handle(), -1), "dds_waitset_attach");
}

void WaitSet::attach(const ReaderBase& reader, int64_t token) {
  Entity cond(detail::check(dds_create_readcondition(reader.handle(), DDS_ANY_STATE),
                            "dds_create_readcondition"));
  detail::check(dds_waitset_attach(waitset_.handle(), cond.handle(), token), "dds_waitset_attach");
  conditions_.push_back(std::move(cond));
}

void WaitSet::attach_liveliness(const ReaderBase& reader, int64_t token) {
  detail::check(dds_set_status_mask(reader.handle(), DDS_LIVELINESS_CHANGED_STATUS),
                "dds_set_status_mask");
  detail::check(dds_waitset_attach(waitset_.handle(), reader.handle(), token),
                "dds_waitset_attach");
}

void WaitSet::wait(std::chrono::nanoseconds timeout, std::vector<int64_t>& out) {
  out.clear();
  std::array<dds_attach_t, 32> xs{};
  const auto n =
      detail::check(dds_waitset_wait(waitset_.handle(), xs.data(), xs.size(), timeout.count()),
                    "dds_waitset_wait");
  for (dds_return_t i = 0; i < n; ++i) {
    const auto token = static_cast<int64_t>(xs[static_cast<size_t>(i)]);
    if (token == -1) {
      bool triggered = false;
      (void)dds_take_guardcondition(guard_.handle(), &triggered);
      continue;
    }
    out.push_back(token);
  }
}

void WaitSet::wake() {
  detail::check(dds_set_guardcondition(guard_.handle(), true), "dds_set_guardcondition");
}

}  // namespace smc::transport
