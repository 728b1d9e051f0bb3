#pragma once
// Real-time thread set-up, in one place (STYLE 13): lock the process's
// memory, pre-fault the calling thread's stack, switch the calling thread to
// SCHED_FIFO and pin it to a CPU. Each step that is refused (no privilege, a
// container without the capability, a bad CPU number) is noted with the
// errno text and skipped: the loop still runs, only with weaker guarantees,
// and the report says which.
//
// Not real-time: everything here runs once, before the loop, and may
// allocate (the report's notes).

#include <cstddef>
#include <string>

#include "smc/common/clock.hpp"

namespace smc::edge::rt {

struct RtOptions {
  // Loop period (2 kHz).
  Nanos period{500'000};
  // SCHED_FIFO priority, 1..99; 0 or less keeps the default SCHED_OTHER.
  int priority = 80;
  // Pin the loop thread to this CPU; -1 leaves the affinity alone.
  int cpu = -1;
  // mlockall(MCL_CURRENT | MCL_FUTURE) for the whole process.
  bool lock_memory = true;
  // A wake-up later than this past its scheduled time is an overrun. Zero or
  // less means one period (the default): a period boundary was missed.
  Nanos overrun_threshold{0};
  // Stack the loop thread touches before its first tick, so that the first
  // deep call does not take page faults (lock_memory keeps it resident).
  std::size_t stack_prefault_bytes = 256 * 1024;
};

// The overrun threshold `opts` means (one period when unset).
inline Nanos effective_overrun_threshold(const RtOptions& opts) noexcept {
  return opts.overrun_threshold > Nanos{0} ? opts.overrun_threshold : opts.period;
}

struct RtSetupReport {
  bool memory_locked = false;  // mlockall succeeded
  bool sched_fifo = false;     // the thread runs SCHED_FIFO ...
  int priority = 0;            // ... at this priority (0 when not FIFO)
  bool affinity = false;       // the thread is pinned to RtOptions::cpu
  bool stack_prefaulted = false;
  // One line per step: what was done, or what was refused and why
  // ("mlockall: Cannot allocate memory (ENOMEM); RLIMIT_MEMLOCK 8192 KiB ...").
  std::string notes;
};

// Not real-time. Applies `opts` to the calling thread (scheduling, affinity,
// stack) and to the process (memory lock). Never throws for a refused step;
// see RtSetupReport::notes. Call it on the thread that will run the loop.
RtSetupReport prepare_realtime_thread(const RtOptions& opts);

// Not real-time. One line for logs and benchmark output, e.g.
// "SCHED_FIFO 80: yes, mlockall: yes, affinity cpu 1: yes".
std::string summary(const RtSetupReport& report, const RtOptions& opts);

}  // namespace smc::edge::rt
