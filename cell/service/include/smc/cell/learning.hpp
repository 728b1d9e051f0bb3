#pragma once
// What the cell learns from a part's runs (cell/README.md, "Learning and
// promotion"): the stability limits its cuts bound, milling models checked
// against them, and the policy that validates a candidate force model by
// how well it predicts the runs after the one it was fitted from.

#include <cstddef>
#include <cstdint>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "smc/cell/store/entities.hpp"
#include "smc/machining/force_process.hpp"
#include "smc_config.pb.h"

namespace smc::cell {

// What a part's cuts showed on one machine, with one tool, at one speed
// (rpm rounded): the deepest chatter-free cut bounds the stability limit
// from below, the shallowest chatter from above.
struct StabilityBound {
  std::string machine_id, tool_id;
  long rpm = 0;
  double stable_mm = 0;  // 0: no chatter-free cut
  double stable_feed_mm = 0;
  std::uint32_t revolutions = 0;  // chatter-free revolutions, all depths
  double chatter_mm = 0;          // 0: no chatter
  double chatter_feed_mm = 0;
  double chatter_hz = 0;
  std::set<std::string> jobs;

  bool has_chatter() const noexcept { return chatter_mm > 0; }
  // A clean cut at or deeper than a chatter: the cuts differed (width,
  // feed) or the machine changed; such a bound validates nothing.
  bool disagrees() const noexcept { return has_chatter() && stable_mm >= chatter_mm; }
};

// The bounds of a part's evidence (Store::stability_evidence), in
// (machine, tool, rpm) order.
std::vector<StabilityBound> stability_bounds(const std::vector<store::StabilityEvidence>& evidence);

// A milling model's time-domain critical depth at each bounding cut's feed
// (with power-law pressures the limit falls with the feed), against the cut.
struct BoundCheck {
  static constexpr double kUnbounded = 1e9;
  double critical_at_chatter_mm = -1;    // -1: the bound has no chatter
  double critical_at_stable_mm = -1;     // -1: the bound has no clean cut
  bool contradicted_by_chatter = false;  // the model puts the chatter below its limit
  bool contradicted_by_stable = false;   // the model puts the clean cut above its limit
  bool contradicted() const noexcept { return contradicted_by_chatter || contradicted_by_stable; }
  // Both ends exist and the model's limit lies between them.
  bool brackets() const noexcept {
    return critical_at_chatter_mm >= 0 && critical_at_stable_mm >= 0 && !contradicted();
  }
};

// Throws std::invalid_argument / ModelError for a model that cannot run.
BoundCheck check_against(const smc::config::MillingModel& model, const StabilityBound& bound);

// A catalog milling model with the tool's cutter and the part's geometry:
// what the planner and the checks above simulate.
smc::config::MillingModel for_part(const store::ProcessModel& model, const store::Tool& tool,
                                   const store::Part& part);

// When a fitted force model is validated: it predicts F_Y of the settled
// revolutions of `runs` consecutive runs after the one it was fitted from
// within `within_pct` (mean absolute error). A run with fewer settled
// revolutions than `min_samples` tells nothing.
struct LearningPolicy {
  double within_pct = 10;
  int runs = 2;
  std::size_t min_samples = 20;
};

// Mean |K d^beta f^alpha - F_Y| / F_Y over the samples, in percent.
double mean_abs_error_pct(const smc::machining::ForceProcessModel& model,
                          std::span<const smc::machining::ForceSample> samples);

// The checks of a model in its catalog history (action "checked", detail
// "passed" or "failed"): how many passed in a row since the last failure,
// suspicion or validation.
int passed_in_a_row(const std::vector<store::CatalogEvent>& history);

}  // namespace smc::cell
