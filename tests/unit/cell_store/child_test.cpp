// A second process on the same database. The parent test starts this binary
// again with posix_spawn (never a bare fork: SQLite connections must not
// cross a fork) running only CellStoreChild.DISABLED_Run, configured by
// SMC_STORE_CHILD_* variables; results go to fd 3, one line each.
//
// Modes:
//   submit-exit  submit one job, report "accepted <id>", _exit(0) with the
//                Store still open (no destructor, no shutdown)
//   submit-hang  submit one job, report, then block until SIGKILLed
//   claim        read the planned jobs, report "ready <n>", wait for the
//                parent's go (a byte on stdin), then try planned -> assigned
//                on $SMC_STORE_CHILD_MACHINE for each; report "won <id>"
//                for each won, then "done"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "smc/cell/store/store.hpp"
#include "store_test_util.hpp"

extern char** environ;

namespace smc::cell::store::test {

namespace {

void say(const std::string& line) {
  const std::string l = line + "\n";
  const char* p = l.data();
  std::size_t left = l.size();
  while (left > 0) {
    const ssize_t n = ::write(3, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) std::_Exit(3);
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? v : "";
}

}  // namespace

Child::Child(const std::string& mode, const std::vector<std::string>& extra_env) {
  int out[2];
  int in[2];
  if (::pipe2(out, O_CLOEXEC) != 0 || ::pipe2(in, O_CLOEXEC) != 0) {
    throw std::runtime_error(std::string("pipe2: ") + std::strerror(errno));
  }
  out_ = out[0];
  hold_ = in[1];
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, in[0], 0);
  posix_spawn_file_actions_adddup2(&fa, out[1], 3);
  // Its gtest banner would only clutter the parent's log; results come on fd 3
  // and failures on stderr.
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);

  std::vector<std::string> args{"/proc/self/exe", "--gtest_also_run_disabled_tests",
                                "--gtest_filter=CellStoreChild.DISABLED_Run"};
  std::vector<std::string> envs{"SMC_STORE_CHILD_MODE=" + mode};
  for (char** e = environ; *e != nullptr; ++e) envs.emplace_back(*e);
  envs.insert(envs.end(), extra_env.begin(), extra_env.end());
  std::vector<char*> argv, envp;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (auto& e : envs) envp.push_back(e.data());
  envp.push_back(nullptr);
  const int rc = posix_spawn(&pid_, "/proc/self/exe", &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  ::close(in[0]);
  ::close(out[1]);
  if (rc != 0) throw std::runtime_error(std::string("posix_spawn: ") + std::strerror(rc));
}

Child::~Child() {
  if (!reaped_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
  ::close(out_);
  ::close(hold_);
}

std::string Child::read_line() {
  for (;;) {
    const auto nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      return line;
    }
    char buf[256];
    const ssize_t n = ::read(out_, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      std::string rest;
      rest.swap(buffer_);
      return rest;
    }
    buffer_.append(buf, static_cast<std::size_t>(n));
  }
}

int Child::wait() {
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  reaped_ = true;
  return status;
}

void Child::kill_hard() { ::kill(pid_, SIGKILL); }

void Child::go() {
  const char c = 'g';
  if (::write(hold_, &c, 1) != 1) throw std::runtime_error("cannot signal the child");
}

// The child's side. Disabled: it runs only when a test spawns it.
TEST(CellStoreChild, DISABLED_Run) {
  const std::string mode = env("SMC_STORE_CHILD_MODE");
  const std::string db = env("SMC_STORE_CHILD_DB");
  ASSERT_FALSE(mode.empty() || db.empty()) << "run only by a parent test";
  try {
    Store store = Store::open(db, OpenMode::kExisting);
    if (mode == "submit-exit" || mode == "submit-hang") {
      smc::config::Job job;
      job.set_part_id(env("SMC_STORE_CHILD_PART"));
      const Job accepted = store.submit_job(job, "submitted by child " + std::to_string(getpid()));
      say("accepted " + accepted.id);
      if (mode == "submit-exit") std::_Exit(0);  // the Store is never closed
      char c;
      while (::read(0, &c, 1) != 0) {
      }  // blocks: the parent holds the write end and kills us
      std::_Exit(4);
    }
    if (mode == "claim") {
      const std::string machine = env("SMC_STORE_CHILD_MACHINE");
      // Both dispatchers see every job planned before either moves one.
      const auto planned = store.jobs({.state = smc::config::JOB_PLANNED});
      say("ready " + std::to_string(planned.size()));
      char go = 0;
      if (::read(0, &go, 1) != 1) std::_Exit(5);
      for (const Job& j : planned) {
        if (store.transition(j.id, smc::config::JOB_PLANNED, smc::config::JOB_ASSIGNED,
                             "claimed by " + machine, machine)) {
          say("won " + j.id);
        }
      }
      say("done");
      std::_Exit(0);
    }
    say("error unknown mode " + mode);
  } catch (const std::exception& e) {
    say(std::string("error ") + e.what());
  }
  std::_Exit(2);
}

}  // namespace smc::cell::store::test
