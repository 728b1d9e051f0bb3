#include "smc/common/log.hpp"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <stdexcept>

namespace smc::log {

namespace {

std::string from_env(const std::string& value, const char* var, const char* fallback) {
  if (!value.empty()) return value;
  const char* env = std::getenv(var);
  return env != nullptr && *env != '\0' ? std::string(env) : std::string(fallback);
}

}  // namespace

void init(const Options& options) {
  const bool from_flag = !options.level.empty();
  const std::string level_name = from_env(options.level, "SMC_LOG_LEVEL", "info");
  const auto level = spdlog::level::from_str(level_name);
  if (level == spdlog::level::off && level_name != "off") {
    throw std::invalid_argument(std::string(from_flag ? "--log-level" : "SMC_LOG_LEVEL") +
                                ": unknown level '" + level_name +
                                "' (use trace, debug, info, warn, error, critical or off)");
  }
  std::string pattern =
      from_env(options.format, "SMC_LOG_FORMAT", "%Y-%m-%dT%H:%M:%S.%e %^%l%$ [%n] %v");
  if (pattern == "json") {
    pattern = R"({"time":"%Y-%m-%dT%H:%M:%S.%f","level":"%l","process":"%n","msg":"%v"})";
  }
  spdlog::drop(options.name);
  std::shared_ptr<spdlog::logger> logger;
  if (options.async) {
    if (!spdlog::thread_pool()) spdlog::init_thread_pool(8192, 1);
    logger = std::make_shared<spdlog::async_logger>(
        options.name, std::make_shared<spdlog::sinks::stderr_color_sink_mt>(),
        spdlog::thread_pool(), spdlog::async_overflow_policy::overrun_oldest);
  } else {
    logger = std::make_shared<spdlog::logger>(
        options.name, std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  }
  logger->set_level(level);
  logger->set_pattern(pattern);
  logger->flush_on(spdlog::level::warn);
  spdlog::set_default_logger(logger);
}

void shutdown() noexcept {
  try {
    spdlog::shutdown();
  } catch (...) {
  }
}

}  // namespace smc::log
