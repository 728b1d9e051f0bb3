// The cell service as a whole, in-process: one cell per database.

#include "smc/cell/service.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "child_process.hpp"
#include "smc/cell/store/seed.hpp"
#include "smc/cell/store/store.hpp"

namespace store = smc::cell::store;

// Issue: two cell services on one database both ran; the losing one exited
// on an invalid transition.
TEST(CellService, ASecondServiceOnTheSameDatabaseRefusesToStartWithTheHoldersPid) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("smc-service-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "cell.db").string();
  {
    auto s = store::Store::open(db);
    store::seed_demo(s);
  }
  smc::cell::ServiceOptions opt;
  opt.db_path = db;
  opt.grafcet_dir = std::string(SMC_SOURCE_DIR) + "/cell/grafcets";
  opt.defaults_file = std::string(SMC_SOURCE_DIR) + "/cell/configs/defaults.textproto";
  opt.partition = smc::test::unique_partition("one-cell");
  {
    smc::cell::CellService first(opt);
    try {
      smc::cell::CellService second(opt);
      FAIL() << "two cells on one database";
    } catch (const store::StoreError& e) {
      const std::string why = e.what();
      EXPECT_NE(why.find("another smc-cell serve (pid " + std::to_string(::getpid()) + ")"),
                std::string::npos)
          << why;
      EXPECT_NE(why.find("fix: stop it first"), std::string::npos) << why;
    }
  }
  // The first one is gone: its lock with it (the kernel releases it however
  // the process ends, so a crash leaves none behind either).
  EXPECT_NO_THROW(smc::cell::CellService again(opt));
  std::filesystem::remove_all(dir);
}
