#pragma once
// SVG plots of a run, in the manner of the paper's Figures 6–8.

#include <string>

#include "smc/edge/runner.hpp"

namespace smc::edge {

// force.svg (F_Y and F_ref over time, pass boundaries, feed-hold and chatter
// marks), feed.svg (commanded feedrate), raw.svg (F_y and F_z samples).
void write_plots(const std::string& dir, const EdgeCore& core, const RunResult& run,
                 const smc::config::RunSummary& summary);

}  // namespace smc::edge
