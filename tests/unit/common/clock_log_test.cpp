#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>

#include "smc/common/clock.hpp"
#include "smc/common/log.hpp"

using namespace std::chrono_literals;

TEST(VirtualClock, MovesOnlyWhenAdvanced) {
  smc::VirtualClock c(smc::Nanos{1000});
  EXPECT_EQ(c.now(), smc::Nanos{1000});
  c.advance(500us);
  EXPECT_EQ(c.now(), smc::Nanos{501000});
  c.sleep_until(smc::Nanos{2'000'000});
  EXPECT_EQ(c.now(), smc::Nanos{2'000'000});
  c.sleep_until(smc::Nanos{10});  // never goes back
  EXPECT_EQ(c.now(), smc::Nanos{2'000'000});
}

TEST(RealClock, SleepUntilReachesTheDeadline) {
  smc::RealClock c;
  const auto t0 = c.now();
  c.sleep_until(t0 + 2ms);
  EXPECT_GE(c.now(), t0 + 2ms);
}

TEST(Seconds, RoundTrip) {
  EXPECT_EQ(smc::from_seconds(0.0005), smc::Nanos{500000});
  EXPECT_DOUBLE_EQ(smc::to_seconds(smc::Nanos{40'000'000}), 0.04);
  EXPECT_EQ(smc::from_seconds(-0.001), smc::Nanos{-1'000'000});
}

TEST(Log, UnknownLevelNamesTheFlag) {
  try {
    smc::log::init({.level = "loud"});
    FAIL() << "an unknown level was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--log-level"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("loud"), std::string::npos);
  }
}

TEST(Log, UnknownLevelFromEnvironmentNamesTheVariable) {
  ::setenv("SMC_LOG_LEVEL", "shouty", 1);
  try {
    smc::log::init({});
    FAIL() << "an unknown level was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SMC_LOG_LEVEL"), std::string::npos) << e.what();
  }
  ::unsetenv("SMC_LOG_LEVEL");
}

TEST(Log, AsyncAndJsonInitialise) {
  EXPECT_NO_THROW(smc::log::init({.level = "debug", .format = "json", .async = true}));
  EXPECT_NO_THROW(smc::log::init({.level = "off"}));
  smc::log::shutdown();
}
