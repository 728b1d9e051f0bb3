#include "label_rule.hpp"

namespace smc::bench {

using smc::edge::kChatterOnsetFlip;
using smc::edge::kChatterOnsetQ;
using smc::edge::RevolutionChange;

bool failed(Outcome o) {
  return o == Outcome::kFalse || o == Outcome::kLate || o == Outcome::kMissed;
}

bool same_failure(Outcome a, Outcome b) {
  return a == Outcome::kFalse ? b == Outcome::kFalse
                              : failed(a) && failed(b) && b != Outcome::kFalse;
}

bool passed_onset_level(const std::vector<RevolutionChange>& changes, size_t at) {
  for (size_t r = at >= 3 ? at - 3 : 0; r <= at && r < changes.size(); ++r) {
    if (changes[r].comparable &&
        (changes[r].q > kChatterOnsetQ || changes[r].flip > kChatterOnsetFlip)) {
      return true;
    }
  }
  return false;
}

Outcome label_rule_outcome(const LabelledCut& cut, std::mt19937_64& rng,
                           std::normal_distribution<double>& error,
                           std::vector<RevolutionChange>& read) {
  read = cut.changes;
  for (RevolutionChange& c : read) {
    c.q *= 1 + error(rng);
    c.flip *= 1 + error(rng);
  }
  smc::edge::mark_onsets(read);
  double decided = -1;
  size_t decided_at = 0;
  for (size_t r = 0; r + 1 < read.size(); ++r) {
    if (!read[r].onset()) continue;
    // A rise confirmed by the next revolution or after a pause; a period
    // doubling by the two after it (or fewer, up to a reaction).
    if (read[r].onset_level > kChatterOnsetQ) {
      const bool grew = !read[r + 1].comparable || read[r + 1].q > read[r].q;
      decided_at = grew || r + 2 >= read.size() ? r + 1 : r + 2;
    } else {
      decided_at = r;
      while (decided_at < r + 2 && decided_at + 1 < read.size() &&
             read[decided_at + 1].comparable) {
        ++decided_at;
      }
    }
    decided = cut.end_s[decided_at];
    break;
  }
  if (cut.onset_s < 0) return decided >= 0 ? Outcome::kFalse : Outcome::kQuiet;
  if (decided < 0) return Outcome::kMissed;
  if (decided < cut.onset_s - 1e-9 && !passed_onset_level(cut.changes, decided_at)) {
    return Outcome::kFalse;  // before the onset, on q that had not reached it
  }
  return (decided - cut.onset_s) * cut.rpm / 60.0 <= 3.0 ? Outcome::kWithin3 : Outcome::kLate;
}

}  // namespace smc::bench
