#include "smc/cell/store/entities.hpp"

#include <array>
#include <cctype>
#include <cstdio>
#include <ctime>

namespace smc::cell::store {

using smc::config::JobState;

bool allowed_transition(JobState from, JobState to) noexcept {
  using namespace smc::config;
  switch (from) {
    case JOB_QUEUED:
      return to == JOB_PLANNED || to == JOB_FAILED;
    case JOB_PLANNED:
      // planned -> queued: the plan is made again (its machine changed).
      return to == JOB_ASSIGNED || to == JOB_FAILED || to == JOB_QUEUED;
    case JOB_ASSIGNED:
      return to == JOB_RUNNING || to == JOB_INTERRUPTED;
    case JOB_RUNNING:
      return to == JOB_DONE || to == JOB_FAILED || to == JOB_INTERRUPTED;
    case JOB_INTERRUPTED:
      return to == JOB_QUEUED || to == JOB_FAILED;
    default:
      return false;  // done and failed are final; unspecified is only a submission's origin
  }
}

bool is_terminal(JobState s) noexcept {
  return s == smc::config::JOB_DONE || s == smc::config::JOB_FAILED;
}

namespace {

constexpr std::array<std::string_view, 8> kStateNames{
    "unspecified", "queued", "planned", "assigned", "running", "done", "failed", "interrupted"};

}  // namespace

std::string_view state_name(JobState s) noexcept {
  const auto i = static_cast<std::size_t>(s);
  return i < kStateNames.size() ? kStateNames[i] : std::string_view("unknown");
}

std::optional<JobState> parse_state(std::string_view text) {
  std::string lower;
  for (const char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.starts_with("job_")) lower.erase(0, 4);
  for (std::size_t i = 1; i < kStateNames.size(); ++i) {
    if (lower == kStateNames[i]) return static_cast<JobState>(i);
  }
  return std::nullopt;
}

std::string_view kind_name(ModelKind k) noexcept {
  return k == ModelKind::kForceProcess ? "force-process" : "milling";
}

std::string_view provenance_name(smc::config::Provenance p) noexcept {
  switch (p) {
    case smc::config::PROVENANCE_HANDBOOK:
      return "handbook";
    case smc::config::PROVENANCE_FITTED:
      return "fitted";
    case smc::config::PROVENANCE_IDENTIFIED:
      return "identified";
    default:
      return "unspecified";
  }
}

std::string_view variant_name(smc::config::SmcVariant v) noexcept {
  switch (v) {
    case smc::config::SMC_NONE:
      return "no process control";
    case smc::config::SMC_I:
      return "SMC I";
    case smc::config::SMC_II:
      return "SMC II";
    case smc::config::SMC_II_PLUS:
      return "SMC II+";
    default:
      return "unspecified";
  }
}

std::string format_time(std::int64_t time_ms) {
  const std::time_t secs = static_cast<std::time_t>(time_ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  std::array<char, 32> buf{};
  const std::size_t n = std::strftime(buf.data(), buf.size(), "%Y-%m-%dT%H:%M:%S", &tm);
  std::array<char, 8> ms{};
  std::snprintf(ms.data(), ms.size(), ".%03dZ", static_cast<int>(time_ms % 1000));
  return std::string(buf.data(), n) + ms.data();
}

std::string channel_text(const WidebandChannel& w) {
  if (w.is_default()) return {};
  char b[96];
  std::snprintf(b, sizeof b, "%g kHz, order-%d filter at %g Hz", w.rate_hz() / 1000, w.order(),
                w.cutoff_hz);
  return b;
}

}  // namespace smc::cell::store
