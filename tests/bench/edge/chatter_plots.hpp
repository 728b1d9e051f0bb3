#pragma once
// The chatter-detector study's figures (smc-bench-chatter-detector --plot
// DIR): what its tables say, drawn.
//
//   chatter-delay.svg     each unstable cut's delay from the label's onset to
//                         E's detection, by speed, width and runout, against
//                         the goal's 3 revolutions (below 0: E decided before
//                         the onset);
//   chatter-margin.svg    the label's margin: each cut's onset level in the
//                         mill's own q, stable cuts below 0.15, unstable at
//                         or above it;
//   chatter-estimate.svg  E's q against the mill's, revolution by revolution;
//   chatter-error.svg     the label's own rule run as a detector on the mill's
//                         q read with an error, beside E.

#include <filesystem>
#include <string>
#include <vector>

namespace smc::bench {

struct ChatterStudyFigures {
  struct Cut {
    double rpm = 0, width = 0, runout = 0;
    bool unstable = false;
    // Unstable: revolutions from the onset to E's first detection (< 0
    // before it), NaN when E missed it. Stable: unused.
    double delay_revs = 0;
    bool detected = false;
    // Unstable: E decided before the onset where the mill's q had not
    // reached it, a false detection (not detected).
    bool premature = false;
    // The mill's q: a stable cut's largest onset level, an unstable cut's
    // onset level (smc/edge/runner.hpp, vibration_change).
    double level = 0;
    // Unstable: the label's onset is a period doubling's, which q does not
    // see (its level is then not q's, and not drawn on the margin).
    bool by_flip = false;
  };
  struct QPair {
    double rpm = 0, mill_q = 0, e_q = 0;
  };
  // The label's rule on q read with an error: mean, fewest and most over
  // the draws.
  struct ErrorRow {
    double sigma = 0;
    double false_mean = 0, late_mean = 0;  // late: unstable cuts not within 3 revolutions
    int false_lo = 0, false_hi = 0, late_lo = 0, late_hi = 0;
  };

  std::string subtitle;  // what was run (the mill, the grid)
  double onset_q = 0.15;
  std::vector<Cut> cuts;
  std::vector<QPair> q_pairs;
  std::vector<ErrorRow> error_rows;
  // E's own figures: its false detections (in stable cuts and before an
  // unstable cut's onset), unstable cuts not within 3 revolutions, all
  // unstable cuts.
  int e_false = 0, e_late = 0, unstable = 0;
};

// "0.3, 0.6, 0.9" and the unit after it, for titles and labels.
std::string joined(const std::vector<double>& values, const char* unit = "");

// Writes the four figures into `dir` (created if missing) and returns their
// paths. Throws std::runtime_error naming the file when one cannot be written.
std::vector<std::filesystem::path> write_chatter_figures(const std::filesystem::path& dir,
                                                         const ChatterStudyFigures& f);

}  // namespace smc::bench
