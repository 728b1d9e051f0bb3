#include "smc/transport/endpoint.hpp"

#include <array>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <thread>

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

ReaderBase::ReaderBase(TopicBase& topic, const QosProfile& qos, MachineOf machine_of)
    : topic_(topic.name()),
      cell_(topic.participant().options().partition),
      machine_of_(machine_of) {
  detail::Qos q;
  detail::apply(qos, q.get());
  entity_ = Entity(detail::check(
      dds_create_reader(topic.participant().subscriber(), topic.handle(), q.get(), nullptr),
      "dds_create_reader", topic.name()));
}

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
          // A writer no longer matched has an unknown partition: its data
          // is refused; an instance-state change (no data) passes.
          const std::string* origin = writer_machine(info.publication_handle);
          const char* key = machine_of_(buf[i]);
          const char* about = key != nullptr ? key : "";
          const bool wrong = origin == nullptr
                                 ? info.valid_data
                                 : !origin->empty() && std::strcmp(origin->c_str(), about) != 0;
          if (wrong) {
            if (refused_++ == 0 || refused_ % 1000 == 0) {
              refusal_handler.load()(
                  "refused on " + topic_ + ": a sample about machine '" + about + "' from " +
                  (origin == nullptr ? std::string("a writer no longer matched")
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

const std::string* ReaderBase::writer_machine(uint64_t publication_handle) {
  auto it = writers_.find(publication_handle);
  if (it != writers_.end()) return &it->second;
  dds_builtintopic_endpoint_t* ep =
      dds_get_matched_publication_data(entity_.handle(), publication_handle);
  if (ep == nullptr) return nullptr;  // not matched (any more): not cached
  // Writers come and go (every edge restart brings new ones): forget them
  // all now and then rather than keep every one ever seen.
  if (writers_.size() >= 4096) writers_.clear();
  std::string machine;
  uint32_t n = 0;
  char** names = nullptr;
  if (ep->qos != nullptr && dds_qget_partition(ep->qos, &n, &names)) {
    for (uint32_t k = 0; k < n; ++k) {
      std::string m = machine_of_partition(cell_, names[k]);
      // In two machines' partitions at once: nobody's.
      if (!m.empty()) machine = machine.empty() ? m : std::string("?");
      dds_free(names[k]);
    }
    dds_free(names);
  }
  dds_builtintopic_free_endpoint(ep);
  return &writers_.emplace(publication_handle, std::move(machine)).first->second;
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
