#pragma once
// Process-wide logging set-up on spdlog. Log calls themselves use spdlog
// directly (spdlog::info(...)) in non-real-time code; the real-time loop
// never logs: it hands events to its comms thread, which does.

#include <string>

namespace smc::log {

struct Options {
  // trace, debug, info, warn, error, critical, off. Empty: $SMC_LOG_LEVEL, else info.
  std::string level;
  // spdlog pattern. Empty: $SMC_LOG_FORMAT, else "%Y-%m-%dT%H:%M:%S.%e %^%l%$ [%n] %v".
  // "json" gives one JSON object per line.
  std::string format;
  // Log through a background thread (bounded queue, drops the oldest when
  // full) so that no caller waits on the terminal or disk.
  bool async = false;
  // Process name shown as [%n].
  std::string name = "smc";
};

// Installs the default logger. Throws std::invalid_argument naming the
// flag or variable when a level is unknown. Safe to call more than once.
void init(const Options& options);

// Flushes and stops the background thread, if any.
void shutdown() noexcept;

}  // namespace smc::log
