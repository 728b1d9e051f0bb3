#pragma once
// Test helper: runs a program as a child process, reads its stdout, kills it.

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace smc::test {

// Path of a program built into build/<preset>/bin, beside the test binary.
inline std::string bin_path(const std::string& name) {
  char buf[4096];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  std::string self(buf, static_cast<size_t>(n));
  return self.substr(0, self.rfind('/')) + "/" + name;
}

// A partition no other test uses, so concurrent tests never see each other.
inline std::string unique_partition(const std::string& tag) {
  return "test-" + tag + "-" + std::to_string(::getpid()) + "-" +
         std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
}

class ChildProcess {
 public:
  explicit ChildProcess(std::vector<std::string> argv) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    const int rc = posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    if (rc != 0) {
      ::close(fds[0]);
      throw std::runtime_error("cannot start " + argv[0]);
    }
    out_ = fds[0];
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    kill(SIGKILL);
    wait();
    if (out_ >= 0) ::close(out_);
  }

  // Reads stdout until a line equal to `line` arrives (true) or EOF (false).
  bool wait_for_line(const std::string& line) {
    std::string cur;
    char c;
    while (::read(out_, &c, 1) == 1) {
      if (c == '\n') {
        if (cur == line) return true;
        cur.clear();
      } else {
        cur.push_back(c);
      }
    }
    return false;
  }

  // The next line of stdout (without its newline), or nothing at EOF.
  std::optional<std::string> read_line() {
    std::string cur;
    char c;
    while (::read(out_, &c, 1) == 1) {
      if (c == '\n') return cur;
      cur.push_back(c);
    }
    if (cur.empty()) return std::nullopt;
    return cur;
  }

  void kill(int sig) {
    if (pid_ > 0 && !exited_) ::kill(pid_, sig);
  }

  int wait() {
    if (pid_ <= 0 || exited_) return status_;
    int st = 0;
    ::waitpid(pid_, &st, 0);
    exited_ = true;
    status_ = st;
    return st;
  }

  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  bool exited_ = false;
  int status_ = 0;
};

}  // namespace smc::test
