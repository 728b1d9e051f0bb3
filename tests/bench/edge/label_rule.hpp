#pragma once
// The detector study's count of the label's own rule run as a detector on
// a cut's q read with an error (smc-bench-chatter-detector; edge/CHATTER.md,
// "Why thresholds cannot meet it" and "E's failures and the label's own
// margin"): what it decides on one cut, counted as E's decisions are.

#include <cstddef>
#include <random>
#include <vector>

#include "smc/edge/runner.hpp"

namespace smc::bench {

// How a detector's first decision on a cut counts against the label: no
// decision in a stable cut; a false detection (in a stable cut, or before
// an unstable cut's onset on q that had not reached it); an unstable cut
// within 3 revolutions, late, or missed.
enum class Outcome { kQuiet, kFalse, kWithin3, kLate, kMissed };
bool failed(Outcome o);
// The same kind of failure: a false detection, or an unstable cut not
// within 3 revolutions (late or missed).
bool same_failure(Outcome a, Outcome b);

// A decision before the label's onset is chatter the label has not called
// yet when the mill's own q, or its period doubling's share, passed the
// onset's threshold in the revolution decided on or the three before it (as
// many as E's rules look at); otherwise it is a false detection, though the
// cut chatters later.
bool passed_onset_level(const std::vector<smc::edge::RevolutionChange>& changes, size_t at);

// A cut's labelling run, revolution by revolution (the mill's own q), kept
// to run the label's own rule again on q read with an error, with how E's
// first decision on the cut counted.
struct LabelledCut {
  double rpm = 0, width = 0, runout = 0, fraction = 0, onset_s = -1;
  int seed = 0;
  std::vector<smc::edge::RevolutionChange> changes;
  std::vector<double> end_s;  // each revolution's last sample
  Outcome e = Outcome::kQuiet;
};

// The label's rule on one cut's q (and share) read with an error drawn
// from `rng` (relative, per revolution), counted against the label on the
// exact q. `read` is scratch, kept by the caller across cuts. It decides
// at the end of the revolution that confirms an onset (the next, or the
// one after a pause; a period doubling's two after it).
Outcome label_rule_outcome(const LabelledCut& cut, std::mt19937_64& rng,
                           std::normal_distribution<double>& error,
                           std::vector<smc::edge::RevolutionChange>& read);

}  // namespace smc::bench
