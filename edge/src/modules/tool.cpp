// Modules beyond Table 1: N (tool-breakage detector) and O (spindle-speed
// chatter suppressor). edge/README.md, "Modules beyond Table 1".

#include <algorithm>
#include <cmath>
#include <numbers>

#include "smc/edge/modules.hpp"

namespace smc::edge {

// ---------------------------------------------------------------- module N

namespace {

// The median of v[0..n), n <= 64. Real-time safe.
double median_of(const double* v, int n) noexcept {
  double sorted[64] = {};
  for (int k = 0; k < n; ++k) {
    int i = k;
    for (; i > 0 && sorted[i - 1] > v[k]; --i) sorted[i] = sorted[i - 1];
    sorted[i] = v[k];
  }
  return n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

}  // namespace

double ToolBreakageDetector::compared_median(int exclude, int& count) const noexcept {
  double v[kMaxTeeth];
  count = 0;
  for (int k = 0; k < p_.teeth; ++k) {
    if (k != exclude && compared_[k]) v[count++] = change_[k];
  }
  return count > 0 ? median_of(v, count) : 0.0;
}

void ToolBreakageDetector::configure(const EdgeParameters& p) {
  if (p.teeth > kMaxTeeth || p.teeth < 1) {
    throw ConfigError(common::Diagnostic{"supervisor_config.operation.teeth",
                                         "module N handles 1 to 64 teeth",
                                         "leave N out for this cutter"});
  }
  p_ = p;
  // A window is a tooth period: at most the longest revolution's share.
  stride_ = std::max(p.max_samples_per_revolution, p.samples_per_revolution) / p.teeth + 2;
  // The windows a tooth's arc in the part spans (the next tooth's gain lies
  // within them of the broken tooth's loss); unknown arc: any window.
  const double window_rad = 2.0 * std::numbers::pi / p.teeth;
  reach_ =
      p.cut_arc_rad > 0
          ? std::clamp(static_cast<int>(std::ceil(p.cut_arc_rad / window_rad - 1e-9)), 1, p.teeth)
          : p.teeth;
  cumulative_.assign(static_cast<size_t>(stride_ * p.teeth), 0.0);
  current_.assign(static_cast<size_t>(stride_), 0.0);
  reset();
}

void ToolBreakageDetector::restart() noexcept {
  std::fill(std::begin(have_previous_), std::end(have_previous_), false);
  std::fill(std::begin(compared_), std::end(compared_), false);
  pending_window_ = -1;
  std::fill(std::begin(change_), std::end(change_), 0.0);
  std::fill(std::begin(excess_), std::end(excess_), 0.0);
  std::fill(std::begin(excess_before_), std::end(excess_before_), 0.0);
  std::fill(std::begin(change_before_), std::end(change_before_), 0.0);
  window_ = -1;
  count_ = 0;
  closed_ = 0;
  most_engaged_ = 0;
  std::fill(std::begin(suspect_drop_), std::end(suspect_drop_), 0.0);
}

void ToolBreakageDetector::reset() noexcept {
  restart();
  unfilled_ = 0;
  last_t_s_ = -1;
  largest_score_ = 0;
}

bool ToolBreakageDetector::adjacent(int a, int b) const noexcept {
  if (a == b) return false;
  const int n = p_.teeth;
  const int d = (a - b + n) % n;
  return std::min(d, n - d) <= reach_;
}

double ToolBreakageDetector::mean_window() const noexcept {
  double total = 0;
  for (int k = 0; k < p_.teeth; ++k) total += previous_[k];
  return total / p_.teeth;
}

double ToolBreakageDetector::relative_common(int exclude) const noexcept {
  double v[kMaxTeeth];
  int count = 0;
  for (int k = 0; k < p_.teeth; ++k) {
    const double base = previous_[k] - change_[k];  // its mean the revolution before
    if (k != exclude && compared_[k] && base > 0) v[count++] = change_[k] / base;
  }
  return count > 0 ? median_of(v, count) : 0.0;
}

void ToolBreakageDetector::judge(Signals& s, double change, double earlier) noexcept {
  const int n = p_.teeth;
  // Settling: the windows have been compared for fewer than
  // kSettleRevolutions (the controller's entry transient moves them).
  const bool settling = closed_ < kSettleRevolutions * n;
  const double window_mean = mean_window();
  if (window_mean < kFloorShare * p_.contact_threshold_n) return;  // too little force to judge
  // With as many samples as it had a revolution before, this window is
  // whole: the window before it can be judged against its neighbours in
  // time now, a sample before this one closes.
  if (count_ == previous_count_[window_]) judge_exit(s, window_, change, earlier + change);
  // The common change: the median of the windows' last changes (of those
  // compared since the (re)start: the others have none yet).
  int compared = 0;
  const double median = compared_median(-1, compared);
  const int peers = compared - (compared_[window_] ? 1 : 0);  // the others compared since then
  // A suspect (see below) is confirmed when another window has taken its
  // chip: risen beyond the common change by half the threshold's share of
  // the mean window (the lost chip shows concentrated in one window, the
  // taken one spread over a window or two: their sizes are not compared).
  const double taken = kConfirmShare * p_.breakage_threshold * window_mean;
  if (change >= 0.5 * taken && change - median >= taken && !s.tool_broken) {
    int confirmed = -1;
    for (int k = 0; k < n; ++k) {
      if (suspect_drop_[k] > 0 && adjacent(window_, k) &&
          (confirmed < 0 || suspect_drop_[k] > suspect_drop_[confirmed]))
        confirmed = k;
    }
    if (confirmed >= 0) {
      s.tool_broken = true;
      s.breakage_window = confirmed;
      s.breakage_drop = suspect_drop_[confirmed];
      return;
    }
  }
  // The other windows' spread about the common change: chatter moves every
  // window a lot, a break one window. The window before this one, if it
  // fell, is left out: a tooth's arc in the part may straddle two windows,
  // and a tooth that broke late in the first lost the rest of its chip in
  // this one.
  const int before = (window_ + n - 1) % n;
  double spread = 0;
  for (int k = 0; k < n; ++k) {
    if (k == window_ || (k == before && change_[k] < median)) continue;
    spread = std::max(spread, std::fabs(change_[k] - median));
  }
  // In a fast common fall (the cutter leaving the part) the median of the
  // revolution's changes lags: the window just closed is the freshest
  // measure of it, and the smaller of the two is taken. A window already
  // falling the revolution before (one side of the cutter leaves first) is a
  // trend, not a break: that fall is taken off (a second difference).
  const double common = compared_[before] ? std::min(median, change_[before]) : median;
  const double excess = common - change;
  // But not leaving the part (engagement below the most the drive reported
  // since the (re)start; NaN: unknown): every fall is then a suspect that
  // another window must take up (below), and at a full slot's exit the
  // window the part's end crossed the revolution before may be the one
  // whose tooth breaks next; its trend would hide the break.
  const bool leaving = leaving_part(s);
  const double trend = leaving ? 0.0 : std::max(0.0, excess_[window_]);
  const double drop = (excess - trend) / window_mean;
  if (excess - trend < kSpreadFactor * spread) return;
  if (s.tool_broken) return;
  // In proportion to each window's own force, too: with runout the windows
  // differ, and a common change (feed, depth, a speed change's restart)
  // moves each by its share, the heaviest most; a tooth that lost its chip
  // loses its own force.
  if (earlier > 0 && relative_common(window_) - change / earlier <= p_.breakage_threshold) return;
  // A certain fall: more than kCertainDrop of a mean window, alone, not
  // leaving the part. Only such a fall decides while settling, and it is a
  // break however the feed moved: a tooth that breaks then is compared with
  // its broken self afterwards and would never be seen.
  const bool certain = drop > kCertainDrop && !leaving;
  // Too few other windows compared yet (the first compared revolution after
  // a (re)start) for a common change: a common fall (a feed running down)
  // would look like a break in the first window. A certain fall waits for
  // them (pending); nothing else decides.
  if (peers < std::min(kMinPeers, n - 1)) {
    if (certain && pending_window_ < 0) {
      pending_window_ = window_;
      pending_mean_ = window_mean;
    }
    return;
  }
  if (settling && !certain) return;
  // Suspects. A feed that fell through the revolution before this window
  // (the controller's entry transient) takes the chip from the teeth that
  // cut least first when the cutter runs out; the cutter leaving the part
  // (engagement below the most the drive reported since the (re)start; NaN:
  // unknown) takes part of one window's arc. Either looks like a break in one
  // window, but no tooth takes the lost chip: the fall must be confirmed by
  // another window's rise (above). A break makes the controller lower the
  // feed only after it, so the revolution before it was steady. Holds do not
  // reach N: it is active only in the cutting step.
  if (!certain && (feed_before_[window_] < (1.0 - kFeedFall) * feed_before2_[window_] || leaving)) {
    if (drop > p_.breakage_threshold && kSuspectFrom * count_ >= previous_count_[window_]) {
      // A suspect lasts a revolution from its window's last fall: a window
      // the part's end made a suspect may fall again when its tooth breaks,
      // and its taker comes after that.
      if (suspect_closed_[window_] != closed_) suspect_drop_[window_] = 0;  // a new fall
      suspect_closed_[window_] = closed_;
      suspect_drop_[window_] = std::max(suspect_drop_[window_], drop);
      // The tooth that took the chip may come first in the revolution (its
      // window closed already, this revolution or the one before): then
      // the suspect is confirmed at once.
      for (int k = 0; k < n; ++k) {
        if (!adjacent(k, window_)) continue;
        // Risen: beyond the common change, and by half as much in itself (in
        // a fast common fall a window that falls less is no tooth taking a
        // chip).
        const double rose = std::max(change_[k] >= 0.5 * taken ? -excess_[k] : 0.0,
                                     change_before_[k] >= 0.5 * taken ? -excess_before_[k] : 0.0);
        if (rose >= taken) {
          s.tool_broken = true;
          s.breakage_window = window_;
          s.breakage_drop = suspect_drop_[window_];
          return;
        }
      }
    }
    return;
  }
  largest_score_ = std::max(largest_score_, drop);
  if (drop <= p_.breakage_threshold) return;
  s.tool_broken = true;
  s.breakage_window = window_;
  s.breakage_drop = drop;
}

void ToolBreakageDetector::judge_pending(Signals& s) noexcept {
  const int w = pending_window_;
  int peers = 0;
  const double median = compared_median(w, peers);
  if (peers < std::min(kMinPeers, p_.teeth - 1)) return;  // not yet
  pending_window_ = -1;
  // The pending window's whole fall against the others' median, and their
  // spread about it: still certain, and alone.
  double spread = 0;
  for (int k = 0; k < p_.teeth; ++k) {
    if (k != w && compared_[k]) spread = std::max(spread, std::fabs(change_[k] - median));
  }
  const double excess = median - change_[w];
  const double drop = excess / pending_mean_;
  if (s.tool_broken || drop <= kCertainDrop || excess < kSpreadFactor * spread) return;
  const double base = previous_[w] - change_[w];
  if (base > 0 && relative_common(w) - change_[w] / base <= p_.breakage_threshold) return;
  largest_score_ = std::max(largest_score_, drop);
  s.tool_broken = true;
  s.breakage_window = w;
  s.breakage_drop = drop;
}

void ToolBreakageDetector::judge_exit(Signals& s, int j, double change_j, double mean_j) noexcept {
  // Leaving the part (the drive's engagement below its most) every window
  // falls, later windows by more or less than earlier ones as the part's
  // end crosses the cutter: the median of a revolution's changes mixes
  // moments of that ramp, and may hide a lost chip that a window's
  // neighbours in time (the window before it and the one after it) do not.
  // Against them, every window is judged with the last sample of the window
  // after it: a fall beyond them by the threshold's share of the mean
  // window is the lost chip, a rise beyond them the tooth that took it (at
  // a full slot's exit the taker falls too, but less than its neighbours:
  // edge/README.md, module N). No taker is needed.
  const int n = p_.teeth;
  if (s.tool_broken || n < 3 || !leaving_part(s)) return;
  const int m = (j + n - 1) % n, b = (j + n - 2) % n;
  if (!compared_[b] || !compared_[m]) return;
  // The windows' latest means, j's as it is now.
  const double window_mean = mean_window() + (mean_j - previous_[j]) / n;
  if (window_mean < kFloorShare * p_.contact_threshold_n) return;
  const double fall = (0.5 * (change_[b] + change_j) - change_[m]) / window_mean;
  const double score = std::fabs(fall);
  largest_score_ = std::max(largest_score_, score);
  if (score <= p_.breakage_threshold) return;
  // A rise: the chip came from a window within the cut's arc of it (the
  // window before it always is), the one that fell most.
  int lost = m;
  if (fall < 0) {
    lost = b;
    double lost_change = change_[b];
    for (int k = 0; k < n; ++k) {
      const double c = k == j ? change_j : change_[k];
      if (adjacent(k, m) && (compared_[k] || k == j) && c < lost_change) {
        lost = k;
        lost_change = c;
      }
    }
  }
  s.tool_broken = true;
  s.breakage_window = lost;
  s.breakage_drop = score;
}

double ToolBreakageDetector::earlier_sum(int j, double x) const noexcept {
  // C(m): the sum of the window's first m samples one revolution ago, linear
  // between whole samples; before its first sample, the sample before it
  // (the window before's last); past its last, its last one's value goes on.
  const int last = previous_count_[j];
  const double* c = &cumulative_[static_cast<size_t>(j * stride_)];
  auto at = [&](int m) { return m <= 0 ? 0.0 : c[m - 1]; };
  if (x <= 0) return x * previous_lead_[j];
  if (x >= last) return at(last) + (x - last) * (at(last) - at(last - 1));
  const int m = static_cast<int>(x);
  return at(m) + (x - m) * (at(m + 1) - at(m));
}

void ToolBreakageDetector::close_window() noexcept {
  const int j = window_;
  const double mean = current_[static_cast<size_t>(count_ - 1)] / count_;
  change_before_[j] = change_[j];
  excess_before_[j] = excess_[j];
  change_[j] = have_previous_[j] ? mean - previous_[j] : 0.0;
  // Its fall beyond the common change, for the next revolution's trend.
  if (have_previous_[j]) {
    compared_[j] = true;
    ++closed_;
  }
  int compared = 0;
  const double median = compared_median(-1, compared);
  excess_[j] = have_previous_[j] ? median - change_[j] : 0.0;
  // A suspect no window confirmed within a revolution: not a break.
  for (int k = 0; k < p_.teeth; ++k) {
    if (suspect_drop_[k] > 0 && closed_ - suspect_closed_[k] > p_.teeth) suspect_drop_[k] = 0;
  }
  previous_[j] = mean;
  feed_before2_[j] = feed_before_[j];
  feed_before_[j] = feed_now_;
  previous_count_[j] = count_;
  previous_offset_[j] = offset_;
  previous_lead_[j] = lead_;
  have_previous_[j] = true;
  std::copy_n(current_.begin(), count_, cumulative_.begin() + static_cast<long>(j) * stride_);
}

Status ToolBreakageDetector::on_sample(Signals& s) noexcept {
  const ForceSample& f = s.sample;
  // A gap in the samples (N was inactive): the windows of before are stale.
  // Nor is the revolution after it filled when N resumes in the cut (a
  // hold): while the feed was held the tool sprang back, and its first
  // revolution back cuts what the deflection had left (edge/README.md,
  // module N). Resuming as the cutter enters the part (the drive's
  // engagement below kFromAir; NaN: unknown, taken as in the cut), nothing
  // sprang back, and the first revolution is a tooth's first shock.
  const bool resumed = last_t_s_ >= 0 && f.t_s - last_t_s_ > 1.5 * p_.sample_period_s;
  if (resumed) {
    restart();
    unfilled_ = s.engagement < kFromAir ? 0.0 : 1.0;
  }
  last_t_s_ = f.t_s;
  feed_now_ = s.feed_per_tooth_cmd_mm;
  if (s.engagement > most_engaged_) most_engaged_ = s.engagement;
  const int n = p_.teeth;
  const double phase = std::clamp(s.revolution_phase, 0.0, 1.0);
  // The revolution clock's step over the last sample (a revolution ends
  // between two samples: the phase carries its remainder over).
  double step = phase - last_phase_;
  if (step <= 0) step += 1.0;
  last_phase_ = phase;
  if (!resumed && unfilled_ > 0) unfilled_ -= step;
  const int w = std::min(n - 1, static_cast<int>(phase * n));
  if (w != window_) {
    if (window_ >= 0 && count_ > 0 && !partial_) {
      const int closed = window_;
      close_window();
      if (pending_window_ >= 0) judge_pending(s);
      if (compared_[closed]) judge_exit(s, closed, change_[closed], previous_[closed]);
    }
    partial_ = window_ < 0 || unfilled_ > 1e-9;
    window_ = w;
    count_ = 0;
    // How far past the window's start (in samples) its first sample lies. A
    // revolution that is not a whole number of samples (1503 rpm at 0.5 ms:
    // 79.84) moves it by a fraction each revolution, and by nearly a whole
    // sample when a revolution is one sample shorter: the teeth's sharp
    // entries then move within the windows' first samples, which looks like
    // a fall. Compared with the revolution before at the same angle, they
    // do not (earlier_sum).
    const double o = (phase - static_cast<double>(w) / n) / step;
    offset_ = step > 0 && step < 0.5 && o >= 0 && o < 2 ? o : 0.0;
    lead_ = last_force_;
  }
  const double force = std::sqrt(f.f_x_n * f.f_x_n + f.f_y_n * f.f_y_n + f.f_z_n * f.f_z_n);
  if (!std::isfinite(force)) return fail("a force sample is not finite");
  last_force_ = force;
  if (count_ >= stride_) return Status::kOk;  // a window longer than the longest revolution's
  current_[static_cast<size_t>(count_)] =
      (count_ > 0 ? current_[static_cast<size_t>(count_ - 1)] : 0.0) + force;
  ++count_;
  // From 1/kJudgeFrom of a window on: this window's samples so far against the same
  // samples of the window one revolution ago.
  const int j = window_;
  if (partial_ || !have_previous_[j] || kJudgeFrom * count_ < previous_count_[j] ||
      count_ > previous_count_[j]) {
    return Status::kOk;
  }
  // The same arc one revolution ago: its samples from `shift` on.
  const double shift = std::clamp(offset_ - previous_offset_[j], -1.0, 1.0);
  const double before = earlier_sum(j, count_ + shift) - earlier_sum(j, shift);
  judge(s, (current_[static_cast<size_t>(count_ - 1)] - before) / count_, before / count_);
  return Status::kOk;
}

// ---------------------------------------------------------------- module O

double SpindleSpeedChatterSuppressor::pick_speed(const EdgeParameters& p, double chatter_hz,
                                                 double programmed_rpm,
                                                 double current_rpm) noexcept {
  if (!(chatter_hz > 0) || !(programmed_rpm > 0) || p.teeth <= 0) return 0;
  const double lo = std::max(p.min_spindle_rpm, programmed_rpm / p.speed_change_max_ratio);
  const double hi = std::min(p.max_spindle_rpm, programmed_rpm * p.speed_change_max_ratio);
  const double aim_hz = (1.0 - p.speed_change_frequency_margin) * chatter_hz;
  // k = 1 is the fastest speed; the first k inside the range is the highest
  // usable pocket (the pockets widen with speed).
  for (int k = 1; k <= 1000; ++k) {
    const double rpm = 60.0 * aim_hz / (p.teeth * k);
    if (rpm < lo) break;
    if (rpm > hi) continue;
    // A speed within 2 % of the one that chatters is no change.
    if (std::fabs(rpm - current_rpm) <= 0.02 * current_rpm) continue;
    return rpm;
  }
  return 0;
}

Status SpindleSpeedChatterSuppressor::update(Signals& s) noexcept {
  if (!started_) {
    started_ = true;
    elapsed_s_ = 0;
    const double programmed =
        program_ != nullptr && program_->current_pass >= 0 &&
                program_->current_pass < program_->program.count
            ? program_->program.passes[static_cast<size_t>(program_->current_pass)].spindle_rpm
            : s.spindle_rpm;
    const double rpm = pick_speed(p_, s.chatter_frequency_hz, programmed, s.spindle_rpm);
    s.spindle_speed_cmd_rpm = rpm;
    s.speed_change_done = rpm == 0;  // nothing to do: the next chatter adds a pass
    return Status::kOk;
  }
  if (s.speed_change_done) return Status::kOk;
  elapsed_s_ += p_.fast_period_s;
  const double cmd = s.spindle_speed_cmd_rpm;
  if (std::fabs(s.spindle_rpm - cmd) <= p_.spindle_at_speed_tolerance * cmd) {
    s.speed_change_done = true;
    return Status::kOk;
  }
  // The spindle did not get there: a module error holds the feed.
  return elapsed_s_ > p_.speed_change_timeout_s
             ? fail(
                   "the spindle did not reach the new speed within "
                   "operation.speed_change_timeout_s")
             : Status::kOk;
}

}  // namespace smc::edge
