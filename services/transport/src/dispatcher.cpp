#include "smc/transport/dispatcher.hpp"

#include <algorithm>

namespace smc::transport {

Dispatcher::Dispatcher(const Participant& participant) : waitset_(participant) {}

void Dispatcher::on(ReaderBase& reader, std::function<void()> serve, Priority priority) {
  add(&reader, std::move(serve), priority);
}

void Dispatcher::poll(std::function<void()> serve, Priority priority) {
  add(nullptr, std::move(serve), priority);
}

void Dispatcher::add(ReaderBase* reader, std::function<void()> serve, Priority priority) {
  if (reader != nullptr) waitset_.attach(*reader, static_cast<int64_t>(handlers_.size()));
  const auto at = std::upper_bound(handlers_.begin(), handlers_.end(), priority,
                                   [](Priority p, const Handler& h) {
                                     return static_cast<int>(p) < static_cast<int>(h.priority);
                                   });
  handlers_.insert(at, Handler{priority, std::move(serve)});
}

void Dispatcher::every(std::chrono::nanoseconds period, std::function<void()> fn) {
  periodic_.push_back({period, std::chrono::steady_clock::now() + period, std::move(fn)});
}

size_t Dispatcher::run_once(std::chrono::nanoseconds timeout) {
  // Never sleep past the next periodic job.
  const auto now = std::chrono::steady_clock::now();
  for (const auto& p : periodic_) {
    timeout = std::min(
        timeout, std::max(std::chrono::nanoseconds{0},
                          std::chrono::duration_cast<std::chrono::nanoseconds>(p.next - now)));
  }
  waitset_.wait(timeout, fired_);
  size_t called = 0;
  // Every reader, in priority order: taking from an empty reader costs a
  // call, and serving all of them keeps a busy reader from hiding another.
  for (auto& h : handlers_) {
    h.serve();
    ++called;
  }
  const auto after = std::chrono::steady_clock::now();
  for (auto& p : periodic_) {
    if (after < p.next) continue;
    p.next = after + p.period;
    p.fn();
    ++called;
  }
  return called;
}

void Dispatcher::wake() { waitset_.wake(); }

}  // namespace smc::transport
