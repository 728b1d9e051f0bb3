#include "smc/edge/rt/rt_setup.hpp"

#include <linux/capability.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace smc::edge::rt {
namespace {

std::string errno_text(int err) {
  const char* desc = strerrordesc_np(err);
  const char* name = strerrorname_np(err);
  std::string s = desc != nullptr ? desc : "unknown error";
  s += " (";
  s += name != nullptr ? name : std::to_string(err);
  s += ")";
  return s;
}

void note(RtSetupReport& r, const std::string& line) {
  if (!r.notes.empty()) r.notes += '\n';
  r.notes += line;
}

// Whether the calling thread holds `cap` in its effective set (capget(2);
// libcap is not needed for one bit).
bool has_capability(unsigned cap) {
  __user_cap_header_struct header{};
  header.version = _LINUX_CAPABILITY_VERSION_3;
  header.pid = 0;
  __user_cap_data_struct data[_LINUX_CAPABILITY_U32S_3]{};
  if (syscall(SYS_capget, &header, data) != 0) return false;
  const unsigned word = cap / 32;
  const unsigned bit = cap % 32;
  if (word >= _LINUX_CAPABILITY_U32S_3) return false;
  return ((data[word].effective >> bit) & 1u) != 0;
}

std::string kib(rlim_t bytes) {
  if (bytes == RLIM_INFINITY) return "unlimited";
  return std::to_string(bytes / 1024) + " KiB";
}

void lock_memory(RtSetupReport& r) {
  rlimit lim{};
  const bool have_limit = getrlimit(RLIMIT_MEMLOCK, &lim) == 0;
  const bool privileged = has_capability(CAP_IPC_LOCK);
  if (!privileged && have_limit && lim.rlim_cur != RLIM_INFINITY) {
    // Under a finite limit MCL_FUTURE turns every later mmap that crosses
    // the limit into an allocation failure anywhere in the process: worse
    // than not locking.
    note(r, "mlockall: skipped: no CAP_IPC_LOCK and RLIMIT_MEMLOCK is " + kib(lim.rlim_cur) +
                " (MCL_FUTURE under a finite limit would make later allocations fail); "
                "page faults may delay the loop");
    return;
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int err = errno;
    note(r, "mlockall(MCL_CURRENT|MCL_FUTURE): " + errno_text(err) + "; RLIMIT_MEMLOCK " +
                (have_limit ? kib(lim.rlim_cur) : std::string("unknown")) +
                (privileged ? ", CAP_IPC_LOCK held" : ", no CAP_IPC_LOCK") +
                "; page faults may delay the loop");
    return;
  }
  r.memory_locked = true;
  note(r, "mlockall(MCL_CURRENT|MCL_FUTURE): ok");
}

// Touches `bytes` of stack below the caller's frame, one write per page.
[[gnu::noinline]] void touch_stack(std::size_t bytes) noexcept {
  auto* p = static_cast<volatile unsigned char*>(__builtin_alloca(bytes));
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  for (std::size_t i = 0; i < bytes; i += page) p[i] = 0;
  if (bytes > 0) p[bytes - 1] = 0;
}

void prefault_stack(RtSetupReport& r, std::size_t bytes) {
  if (bytes == 0) return;
  // Stay well inside the thread's stack.
  pthread_attr_t attr;
  std::size_t stack_size = 0;
  if (pthread_getattr_np(pthread_self(), &attr) == 0) {
    pthread_attr_getstacksize(&attr, &stack_size);
    pthread_attr_destroy(&attr);
  }
  const std::size_t margin = 64 * 1024;
  if (stack_size > 0 && bytes + margin > stack_size) {
    const std::size_t limited = stack_size > 2 * margin ? stack_size - 2 * margin : 0;
    note(r, "stack pre-fault: " + std::to_string(bytes / 1024) + " KiB asked, thread stack is " +
                std::to_string(stack_size / 1024) + " KiB; touching " +
                std::to_string(limited / 1024) + " KiB");
    bytes = limited;
  }
  if (bytes == 0) return;
  touch_stack(bytes);
  r.stack_prefaulted = true;
}

void configure_sched_fifo(RtSetupReport& r, int priority) {
  if (priority <= 0) {
    note(r, "SCHED_FIFO: not requested (priority " + std::to_string(priority) +
                "); the loop runs SCHED_OTHER");
    return;
  }
  const int lo = sched_get_priority_min(SCHED_FIFO);
  const int hi = sched_get_priority_max(SCHED_FIFO);
  if (priority < lo || priority > hi) {
    note(r, "SCHED_FIFO: priority " + std::to_string(priority) + " outside " + std::to_string(lo) +
                ".." + std::to_string(hi) + "; the loop runs SCHED_OTHER");
    return;
  }
  sched_param param{};
  param.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc != 0) {
    rlimit lim{};
    std::string rtprio = "unknown";
    if (getrlimit(RLIMIT_RTPRIO, &lim) == 0) {
      rtprio = lim.rlim_cur == RLIM_INFINITY ? "unlimited" : std::to_string(lim.rlim_cur);
    }
    note(r, "SCHED_FIFO " + std::to_string(priority) + ": " + errno_text(rc) + "; RLIMIT_RTPRIO " +
                rtprio +
                (has_capability(CAP_SYS_NICE) ? ", CAP_SYS_NICE held" : ", no CAP_SYS_NICE") +
                " (a cgroup without a real-time budget also refuses); the loop runs SCHED_OTHER");
    return;
  }
  int policy = 0;
  sched_param now{};
  if (pthread_getschedparam(pthread_self(), &policy, &now) == 0 && policy == SCHED_FIFO) {
    r.sched_fifo = true;
    r.priority = now.sched_priority;
    note(r, "SCHED_FIFO " + std::to_string(now.sched_priority) + ": ok");
  } else {
    note(r, "SCHED_FIFO " + std::to_string(priority) + ": accepted but not in effect");
  }
}

void pin_to_cpu(RtSetupReport& r, int cpu) {
  if (cpu < 0) return;
  if (cpu >= CPU_SETSIZE) {
    note(r, "affinity: cpu " + std::to_string(cpu) + " out of range");
    return;
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(static_cast<std::size_t>(cpu), &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  if (rc != 0) {
    note(r, "affinity cpu " + std::to_string(cpu) + ": " + errno_text(rc) +
                " (not online, or outside this process's cpuset)");
    return;
  }
  r.affinity = true;
  note(r, "affinity cpu " + std::to_string(cpu) + ": ok");
}

}  // namespace

RtSetupReport prepare_realtime_thread(const RtOptions& opts) {
  RtSetupReport r;
  // Pin first, so that the stack pages and later allocations come from the
  // loop CPU's node; lock before touching the stack so the touched pages stay.
  pin_to_cpu(r, opts.cpu);
  if (opts.lock_memory) {
    lock_memory(r);
  } else {
    note(r, "mlockall: not requested");
  }
  prefault_stack(r, opts.stack_prefault_bytes);
  configure_sched_fifo(r, opts.priority);
  return r;
}

std::string summary(const RtSetupReport& report, const RtOptions& opts) {
  // Appended piece by piece: GCC 12 reports a false -Wrestrict on
  // `"literal" + std::string&&` at -O3.
  std::string s = "SCHED_FIFO";
  if (opts.priority > 0) {
    s += ' ';
    s += std::to_string(opts.priority);
  }
  s += report.sched_fifo ? ": yes" : ": no";
  s += ", mlockall: ";
  s += opts.lock_memory ? (report.memory_locked ? "yes" : "no") : "not requested";
  if (opts.cpu >= 0) {
    s += ", affinity cpu ";
    s += std::to_string(opts.cpu);
    s += report.affinity ? ": yes" : ": no";
  }
  return s;
}

}  // namespace smc::edge::rt
