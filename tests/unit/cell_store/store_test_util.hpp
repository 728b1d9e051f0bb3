#pragma once
// Shared fixture for the cell store tests: a fresh folder per test, helpers
// to write files and to run this test binary as a child process (a second
// process on the same database: another CLI, another dispatcher, a crash).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"

namespace smc::cell::store::test {

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::path(::testing::TempDir()) /
           ("smc_cell_store_" + std::to_string(::getpid())) /
           (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (HasFailure()) return;  // kept for a look
    std::filesystem::remove_all(dir_);
    std::error_code ignored;  // the per-process folder goes once empty
    std::filesystem::remove(dir_.parent_path(), ignored);
  }

  std::string db_path() const { return (dir_ / "cell.db").string(); }
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  // A seeded store with the built-in paper values (independent of cell/models/).
  Store seeded() const {
    Store s = Store::open(db_path());
    seed_demo(s, SeedOptions{});
    return s;
  }

  std::filesystem::path dir_;
};

inline std::string repo_file(const std::string& rel) {
  return std::string(SMC_SOURCE_DIR) + "/" + rel;
}

// Runs this test binary's child helper (child_test.cpp) with the given mode
// and environment. The child writes one line per result to the pipe it gets
// as fd 3; read_line() returns them.
class Child {
 public:
  Child(const std::string& mode, const std::vector<std::string>& env);
  ~Child();
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  std::string read_line();  // "" at end of output
  int wait();               // exit status as from waitpid
  void kill_hard();         // SIGKILL (the child is blocked, waiting for it)
  void go();                // one byte on the child's stdin
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int out_ = -1;   // read end of the child's fd 3
  int hold_ = -1;  // write end of the child's stdin, never written: it blocks there
  std::string buffer_;
  bool reaped_ = false;
};

}  // namespace smc::cell::store::test
