#include "smc/cell/learning.hpp"

#include <cmath>
#include <map>
#include <tuple>

#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"

namespace smc::cell {

std::vector<StabilityBound> stability_bounds(
    const std::vector<store::StabilityEvidence>& evidence) {
  std::map<std::tuple<std::string, std::string, long>, StabilityBound> by;
  for (const auto& e : evidence) {
    const auto key = std::make_tuple(e.machine_id, e.tool_id, std::lround(e.spindle_rpm));
    auto& b = by[key];
    b.machine_id = e.machine_id;
    b.tool_id = e.tool_id;
    b.rpm = std::get<2>(key);
    if (e.chatter) {
      if (!b.has_chatter() || e.depth_mm < b.chatter_mm) {
        b.chatter_mm = e.depth_mm;
        b.chatter_feed_mm = e.feed_per_tooth_mm;
        b.chatter_hz = e.frequency_hz;
      }
    } else {
      if (e.depth_mm > b.stable_mm) {
        b.stable_mm = e.depth_mm;
        b.stable_feed_mm = e.feed_per_tooth_mm;
      }
      b.revolutions += e.revolutions;
    }
    b.jobs.insert(e.job_id);
  }
  std::vector<StabilityBound> out;
  out.reserve(by.size());
  for (auto& [key, b] : by) out.push_back(std::move(b));
  return out;
}

BoundCheck check_against(const smc::config::MillingModel& model, const StabilityBound& b) {
  const auto m = smc::machining::from_proto(model, "milling_model");
  auto limit = [&](double feed) {
    const auto c =
        smc::machining::critical_depth_tds(m, static_cast<double>(b.rpm), feed > 0 ? feed : 0.1);
    return c.bounded ? c.critical_depth_mm : BoundCheck::kUnbounded;
  };
  BoundCheck out;
  if (b.has_chatter()) {
    out.critical_at_chatter_mm = limit(b.chatter_feed_mm);
    out.contradicted_by_chatter = out.critical_at_chatter_mm > b.chatter_mm + 1e-6;
  }
  if (b.stable_mm > 0) {
    out.critical_at_stable_mm = limit(b.stable_feed_mm);
    out.contradicted_by_stable = out.critical_at_stable_mm < b.stable_mm - 1e-6;
  }
  return out;
}

smc::config::MillingModel for_part(const store::ProcessModel& model, const store::Tool& tool,
                                   const store::Part& part) {
  smc::config::MillingModel mm = model.milling;
  mm.mutable_cutter()->set_teeth(tool.teeth);
  mm.mutable_cutter()->set_radius_mm(tool.radius_mm);
  mm.mutable_cutter()->set_lead_angle_deg(tool.lead_angle_deg);
  mm.mutable_workpiece()->set_width_mm(part.width_mm);
  mm.mutable_workpiece()->set_offset_mm(part.offset_mm);
  mm.mutable_workpiece()->set_length_mm(part.length_mm);
  return mm;
}

double mean_abs_error_pct(const smc::machining::ForceProcessModel& model,
                          std::span<const smc::machining::ForceSample> samples) {
  double sum = 0;
  std::size_t n = 0;
  for (const auto& s : samples) {
    if (!(s.force_n > 0)) continue;
    const double p = model.force_n(s.depth_mm, s.feed_mm_per_tooth);
    if (!std::isfinite(p)) continue;
    sum += std::fabs(p - s.force_n) / s.force_n;
    ++n;
  }
  return n == 0 ? std::nan("") : 100.0 * sum / static_cast<double>(n);
}

int passed_in_a_row(const std::vector<store::CatalogEvent>& history) {
  int n = 0;
  for (const auto& e : history) {
    if (e.action == "checked") {
      n = e.detail == "passed" ? n + 1 : 0;
    } else if (e.action == "suspected" || e.action == "validated") {
      n = 0;
    }
  }
  return n;
}

}  // namespace smc::cell
