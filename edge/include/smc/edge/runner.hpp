#pragma once
// Virtual-time runs of the edge core (smc-edge simulate, tests, benchmarks):
// the same core and modules as on the machine, stepped by a virtual clock as
// fast as the CPU allows. Deterministic.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "smc/edge/core.hpp"

namespace smc::config {
class RunSummary;
}

namespace smc::edge {

// An operator action at a machine time.
struct ScheduledInput {
  enum Kind { kFeedHoldOn, kFeedHoldOff, kChatterSignal } kind;
  double t_s;
};

struct RunOptions {
  double max_time_s = 600;             // stop even if the program is not done
  std::vector<ScheduledInput> inputs;  // sorted or not; applied in time order
  // Called after every tick (tests use it to check invariants at each step).
  std::function<void(const EdgeCore&)> on_tick;
  // Called before every tick: a drive paced by a real machine waits there for
  // its next sample (the LinuxCNC drive). Returning false ends the run.
  std::function<bool()> before_tick;
  // A broken tool (module N) is the end of the run: it goes on this long
  // after the event (the feed held), then stops.
  double after_breakage_s = 1.0;
  bool keep_samples = true;   // keep the per-sample trace
  int sample_decimation = 1;  // keep every n-th sample
  // Keep the vibration between samples where the drive gives it
  // (DriveSample::vibration_count; RunResult::vibration_sub_mm), for the
  // label. Only with every sample kept.
  bool keep_vibration_between_samples = true;
};

// One kept sample of the trace.
struct TraceSample {
  double t_s;
  double x_mm;
  double f_y_n;
  double f_z_n;
  double f_y_wide_n;  // NaN: the drive has no wideband F_y channel
  double f_y_peak_n;
  double f_ref_n;
  double feedrate_mm_s;
  double depth_mm;
  double spindle_rpm;
  double power_w;
  double vibration_y_mm;
  double engagement;
  int16_t pass_index;
  bool in_pass;
  bool contact;
  ModuleMask active;
  uint64_t steps;
};

struct RunResult {
  std::vector<TraceSample> samples;
  std::vector<RevolutionRecord> revolutions;
  std::vector<EdgeEvent> events;
  double end_time_s = 0;
  bool completed = false;
  double tool_broken_s = -1;  // module N's event, -1: none
  uint64_t ticks = 0;
  // The vibration at the drive's faster rate, where it gives one
  // (DriveSample::vibration_count, the same at every sample):
  // vibration_per_sample values for each of `samples`, oldest first, the
  // last of each being its vibration_y_mm. Empty (vibration_per_sample 1)
  // otherwise: the label then reads the vibration at the sample period.
  int vibration_per_sample = 1;
  std::vector<double> vibration_sub_mm;
};

// Runs `core` (already start()ed) until its program is done or max_time_s.
RunResult run_virtual(EdgeCore& core, const RunOptions& options);

// Figures of merit of a run (what summary.json holds).
smc::config::RunSummary summarize(const EdgeCore& core, const RunResult& run);

// The simulated vibration's change from one revolution to the next, which
// labels chatter independently of module E (the summary's chatter onset):
// per revolution of the trace (by the spindle speed it records; at a still
// spindle, still_period_s), q = RMS(v_k - v_k-1) / RMS(v_k) of the relative
// tool-part vibration (at the run's vibration_per_sample times the sample
// rate where it has the vibration between samples, as it does when the
// simulated mill's wideband channel samples faster than the loop; at the
// sample rate otherwise), whether it is comparable with the revolution before
// (both fully in the cut, no hold, not leaving the part), and its onset
// level: the largest threshold at which it would be the onset (above the
// threshold and above the revolution before, then larger still -- or, after
// one revolution above the threshold, larger than it; or not comparable
// any more, a reaction or the pass's end). 0 where it would be at none.
//
// q cannot see a period doubling once it has grown: with an even number of
// teeth, a vibration at the spindle orders halfway between tooth harmonics
// repeats every revolution. So with `teeth` even, each revolution also has
// `flip`, that vibration's share of the revolution's AC energy, and its
// flip onset level: the least share of it and the next two revolutions
// (fewer where the next is not comparable any more, a reaction or the
// pass's end), on comparable revolutions; 0 elsewhere.
//
// The onset is the first revolution whose onset level exceeds
// kChatterOnsetQ or whose flip onset level exceeds kChatterOnsetFlip.
//
// With `forced` (one value per sample of the run: the vibration of the same
// cut on a mill without regeneration, fed the same way; forced_vibration),
// q is of the vibration regeneration adds, v - forced, still over RMS(v_k):
// the change from one revolution to the next that the forced vibration does
// not explain. The detector study's --twin-label; the summary's onset does
// not use it. With `forced` the label reads the sample rate alone.
struct RevolutionChange {
  size_t first_sample = 0, end_sample = 0;  // [first, end) in RunResult::samples
  double q = 0;
  bool comparable = false;
  double onset_level = 0;
  double flip = 0;
  double flip_onset_level = 0;
  bool onset() const noexcept;
};
inline constexpr double kChatterOnsetQ = 0.15;
inline constexpr double kChatterOnsetFlip = 0.5;
inline bool RevolutionChange::onset() const noexcept {
  return onset_level > kChatterOnsetQ || flip_onset_level > kChatterOnsetFlip;
}
std::vector<RevolutionChange> vibration_change(const RunResult& run, double still_period_s,
                                               int teeth = 0,
                                               const std::vector<double>* forced = nullptr);
// The time of the first revolution of `changes` (vibration_change of `run`)
// that is the onset; -1: none. The summary's chatter onset is this.
double first_onset_s(const RunResult& run, const std::vector<RevolutionChange>& changes);
// The vibration of `run`'s cut replayed on `twin`: the feed the core
// commanded at each sample of the run (kept with every sample, the trace
// not decimated) applied to `twin`, a drive that has loaded the run's
// program and not stepped yet; one value per sample. Throws
// std::runtime_error naming the sample where the twin's position or pass
// parts from the run's (a run whose program was rewritten, or a spindle
// speed changed, cannot be replayed so). Not real-time.
std::vector<double> forced_vibration(const RunResult& run, Drive& twin);
// Sets each revolution's onset_level and flip_onset_level from the q, flip
// and comparable of the revolutions around it (the rules above;
// vibration_change calls it). The
// detector study runs it again on q read with an error, to measure how
// much the label's own decision depends on q's last per cent.
void mark_onsets(std::vector<RevolutionChange>& changes);

// Writes samples.csv, revolutions.csv, events.csv, summary.json and the plots
// (force.svg: F_Y with F_ref, pass boundaries, feed-hold and chatter marks;
// feed.svg; raw.svg) into `dir` (created if needed). Throws on I/O errors
// naming the file.
void write_outputs(const std::string& dir, const EdgeCore& core, const RunResult& run,
                   const smc::config::RunSummary& summary);

// Parses "T:DURATION" (seconds) as a feed hold from T to T+DURATION.
// Throws std::invalid_argument naming the flag and the expected form.
std::vector<ScheduledInput> parse_feed_hold(const std::string& spec);

}  // namespace smc::edge
