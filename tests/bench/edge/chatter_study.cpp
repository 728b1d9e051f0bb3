// Module E on stable and unstable cuts across spindle speeds, widths of cut
// and depths: false detections and detection delay.
//
//   build/release/bin/smc-bench-chatter-detector [--seeds N] [--speeds 750,1100,...]
//       [--widths 25,37,50] [--fractions 0.3,0.6,0.9,1.3,1.8] [--runouts 0,10,20]
//       [--quick] [--verbose] [--plot DIR] [--dump FILE.csv] [--dump-samples STEM]
//       [--force-only] [--vibration-rise X] [--vibration-climb X] [--vibration-pause X]
//       [--vibration-growth X] [--vibration-net X] [--vibration-net-growth X]
//       [--vibration-net-dip X] [--vibration-jump X] [--vibration-jump-growth X]
//       [--vibration-jump-dip X] [--vibration-steep X] [--vibration-steep-growth X]
//       [--vibration-steep-from X] [--vibration-confirmed X]
//       [--vibration-confirmed-growth X] [--vibration-level X] [--vibration-held X]
//       [--vibration-held-floor X] [--vibration-flip X]
//       [--vibration-backup X] [--vibration-flip-revolutions N] [--vibration-forget-across-steps]
//       [--vibration-noise N] [--channel-noise N] [--wide-cutoff HZ] [--wide-order N]
//       [--wide-samples N] [--sample-period S] [--mill-model FILE] [--no-regeneration]
//       [--twin-label] [--tick-label] [--edge-knows-the-mill] [--edge-tool-modes-only]
//
// --help lists every flag with what it does and its default.
//
// Runs the shipped SMC II configuration on the simulated mill, one pass per
// run at 0.1 mm/tooth programmed. For each speed and width the critical depth
// at that feed is found first by time-domain simulation (smc::machining), and
// the pass depths are the given fractions of it; each cut is run with every
// cutter runout given (um, eccentric mounting: services/machining README,
// "Runout"; the critical depth is the runout-free one). Whether a cut is stable is
// decided from the simulated vibration, independently of E: each cut runs
// twice, first with E's rules switched off, whose run summary's chatter
// onset labels it, then with E as it ships, whose first detection is what E
// decides before anything reacts. (Labelled from the second run, a false
// detection would make its own onset: the summary takes a rising
// revolution followed by the hold that reacts to it as the start of
// chatter.) Stable cuts give the false-alarm figures
// (revolutions in the cut whose statistic exceeded the threshold, confirmed
// detections, the largest statistic), unstable cuts the delay from the onset
// to E's detection, in revolutions. The label's onset is q's, or with an
// even number of teeth a period doubling's (its share of the vibration's
// energy above 0.5 for three revolutions; q cannot see it once grown:
// smc/edge/runner.hpp). A detection before the onset is chatter the label
// has not called yet (within 3 revolutions) where the mill's q passed the
// onset's 0.15, or that share 0.5, in the revolution decided on or the
// three before it, and a false detection where it did not. E judges the vibration it estimates
// from the simulated dynamometer's wideband F_y channel (S's backup off as
// shipped: --vibration-backup 0.7 puts it back; the S_above column counts
// stable revolutions above 0.7 all the same; edge/CHATTER.md, "S's backup
// is off"); --force-only takes the estimate away
// (S alone, as on a sensor without that channel), --vibration-* set its
// rules' parameters, and --vibration-noise the channel noise it takes out
// (N rms; the configuration's operation.wideband_noise_rms_n otherwise).
// --channel-noise N: the simulated dynamometer's white noise on every force
// channel (simulation.noise_rms_n, 2 N rms in the configuration), and the
// noise E takes out with it unless --vibration-noise says otherwise; 0 shows
// what E's estimate does without it. --wide-cutoff HZ and --wide-order N:
// the simulated wideband F_y channel's anti-alias filter (a Butterworth,
// even order 2-8; the configuration's 3.5 kHz, eighth order) and what E is
// told of it. --sample-period S: the edge samples every S seconds
// (operation.sample_period_s; the configuration's 0.0005, the paper's 2 kHz),
// and the wideband channel E reads and the vibration the label reads are
// sampled that many times a period; with --wide-samples 1, 0.00025 shows
// what E and the label make of a channel sampled twice as fast.
// --wide-samples N: the wideband channel alone samples N times a sample
// period (simulation.f_y_wide_samples_per_tick and
// operation.wideband_samples_per_tick; the configuration's 5, 10 kHz at 0.5
// ms; 1 is the paper's rate): E reads it at that rate while the loop and F_z
// stay at the sample period, E's rules are the set chosen for that rate
// (set_vibration_rules_for_channel), and the label reads the mill's
// vibration at the channel's rate too (RunResult::vibration_sub_mm) unless
// --tick-label keeps it at the sample period.
// --mill-model FILE: the
// simulated mill cuts with that model's structure and cutting law (e.g.
// cell/models/paper_face_mill_mismatched.textproto), while E and the
// critical depths keep the configuration's; with --edge-knows-the-mill E
// undoes that model's structure instead (a tap test on the machine itself).
// --edge-tool-modes-only: E undoes the configuration's tool modes alone, not
// the part's (edge/CHATTER.md, "The structure E is given"). --no-regeneration: the mill
// cuts every chip at its nominal thickness (simulation.no_regeneration), so
// no cut can chatter and the vibration is the forced response alone: every
// onset the label finds then is one it should not, and every detection a
// false one. --twin-label: each labelling run's feed is replayed on the same
// mill without regeneration (forced_vibration, smc/edge/runner.hpp), and
// the label's q is of what regeneration adds to the vibration, v less the
// twin's, over RMS(v) (the mill's q in the figures below is that q too):
// a forced vibration that changes in the entry is no onset on it. After
// the tables: the unstable
// cuts E caught late or missed, each with the mill's own q around its onset
// (how long it stayed above the onset's threshold, and how high it went
// after); the unstable cuts E detected before the label's onset (within 3
// revolutions, or false detections: above), each with the mill's own q
// around E's detection and how it is counted;
// the label's own margin (the largest onset level of a stable cut and the smallest of
// an unstable cut's onset, in the mill's q: smc/edge/runner.hpp,
// vibration_change); the period doubling's onsets (how many it called
// before q, or alone), its margin in the share, and E's share against the
// mill's; the label's own rules run as a detector on the mill's
// q and share read with a relative error of 0-10 % drawn per revolution (5 draws
// each, counted as E's decisions are: how exact a reading of q the goal
// asks for on these labels), and which of E's own false detections and
// late or missed cuts that rule makes too on the same cut's q read with an
// error of 0.5, 1 and 2 % (in at least 5 of 100 draws; those it does not
// at 1 % are listed): a failure of E's that a reading of q within 1 % of
// the mill's makes too, one time in twenty or more, lies inside the
// label's own margin; E's q against the mill's on the labelling runs'
// comparable revolutions with the mill's q in 0.10-0.30, by speed; then
// E's q where the mill's is below 0.02 (a cut that repeats itself, before
// any onset), by speed: what the channel's noise alone makes of q there
// (--channel-noise 0 shows it without). --plot DIR draws the delays, the
// label's margin, E's q against the mill's and the label's rule on q with an
// error into DIR (chatter_plots.hpp). Progress goes to stderr. --dump writes
// every revolution of the labelling run (E's rules off) that E judged or
// skipped in contact (statistic, q, engagement, feed, the mill's own q
// on the trace's revolution that ends there, -1 where it is not
// comparable, and E's period-doubling share) with its onset, to
// try other decision rules offline: what happens before E's first
// detection does not depend on the rule. --threshold 1 switches E's rules
// off in both runs (and runs each cut once). --dump-samples STEM writes
// the labelling run's samples and revolutions, to try other statistics offline:
// STEM.runs.csv (one line per run: its grid point, onset and detection
// times, and where its records start in the two binary files and how many
// there are), STEM.samples.bin (25-byte records, little-endian: t_s f64,
// F_z f32, feed rate f32, relative vibration y f32, wideband F_y f32, flags
// u8 -- bit 0 contact, bit 1 E active, bit 2 in a pass) and STEM.revs.bin (17-byte
// records: t_s f64, E's statistic f32, feed per tooth f32, flags u8 -- bit
// 0 contact, bit 1 E active). A revolution's samples are those after the
// revolution before, up to its own t_s.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "chatter_plots.hpp"
#include "label_rule.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/tds.hpp"
#include "smc_config.pb.h"
#include "study_grid.hpp"

using namespace smc::edge;
using smc::bench::failed;
using smc::bench::label_rule_outcome;
using smc::bench::LabelledCut;
using smc::bench::Outcome;
using smc::bench::passed_onset_level;
using smc::bench::same_failure;

namespace {

struct Cell {
  double rpm = 0, width = 0, runout = 0;
  int runs = 0, stable_runs = 0, unstable_runs = 0, detected = 0, false_detections = 0;
  int premature = 0;  // of the false detections, those before an unstable cut's onset
  uint64_t stable_revs = 0, exceed = 0;
  int within3 = 0;
  double stable_max = 0, stable_max_q = 0, worst_delay_revs = 0, unstable_min_peak = 1e9;
};

// An unstable cut E caught late or missed, with the mill's own q around its
// onset (the labelling run's): what kind of onset it was.
struct LateCut {
  double rpm = 0, width = 0, runout = 0, fraction = 0;
  int seed = 0;
  double delay_revs = -1;  // -1: missed
  std::vector<double> q;   // the mill's q from the revolution before the onset, up to 6
  int above = 0;           // revolutions from the onset on with q above the onset's 0.15
  double later_most = -1;  // the largest q after those, to the end of the pass (-1: none)
  bool by_flip = false;    // the onset a period doubling's: the values are its share, not q
};

// q values in columns, "-" for one that is not comparable (< 0).
std::string q_list(const std::vector<double>& qs) {
  std::string out;
  char one[16];
  for (const double q : qs) {
    if (q < 0) {
      std::snprintf(one, sizeof one, "%6s ", "-");
    } else {
      std::snprintf(one, sizeof one, "%6.3f ", q);
    }
    out += one;
  }
  return out;
}

// An unstable cut E detected before the label's onset, with the mill's own
// q (the labelling run's) from three revolutions before E's detection to
// the one after: was the cut already changing when E decided?
struct EarlyCut {
  double rpm = 0, width = 0, runout = 0, fraction = 0;
  int seed = 0;
  double delay_revs = 0;  // < 0
  std::vector<double> q;
  double most_before_onset = 0;  // the mill's largest q from E's detection to the onset
  bool premature = false;        // !passed_onset_level: a false detection
};

// The label's own rule run as a detector on each cut's q read with a
// relative error drawn per revolution (Gaussian, sigma): what it decides,
// counted as E's decisions are. It decides at the end of the revolution
// that confirms an onset (the next, or the one after a pause).
struct RuleOnError {
  int false_detections = 0, detected = 0, within3 = 0;
};
RuleOnError label_rule_on_error(const std::vector<LabelledCut>& cuts, double sigma, unsigned draw) {
  std::mt19937_64 rng(draw);
  std::normal_distribution<double> error(0.0, sigma);
  RuleOnError out;
  std::vector<RevolutionChange> read;
  for (const LabelledCut& cut : cuts) {
    switch (label_rule_outcome(cut, rng, error, read)) {
      case Outcome::kFalse:
        ++out.false_detections;
        break;
      case Outcome::kWithin3:
        ++out.within3;
        ++out.detected;
        break;
      case Outcome::kLate:
        ++out.detected;
        break;
      case Outcome::kQuiet:
      case Outcome::kMissed:
        break;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  smc::bench::StudyGrid grid;
  grid.seeds = 2;
  grid.fractions = {0.3, 0.6, 0.9, 1.3, 1.8};
  grid.runouts = {0};
  double threshold_override = 0;
  int confirm_override = 0;
  bool force_only = false;
  bool no_regeneration = false;
  bool twin_label = false;
  bool tick_label = false;
  bool edge_knows_the_mill = false;
  bool edge_tool_modes_only = false;
  double channel_noise = -1;  // < 0: the configuration's
  double wide_cutoff = -1;    // < 0: the configuration's
  double sample_period = -1;  // < 0: the configuration's
  int wide_order = 0;         // 0: the configuration's
  int wide_samples = 0;       // 0: the configuration's
  // E's parameters the study may override (< 0: the shipped value).
  struct Knob {
    const char* flag;
    double EdgeParameters::*field;
    const char* what;
    double value = -1;
  };
  Knob knobs[] = {
      {"--vibration-rise", &EdgeParameters::chatter_vibration_rise, "the rise rule's level of q"},
      {"--vibration-climb", &EdgeParameters::chatter_vibration_climb,
       "the climb rule's level (three rises in a row)"},
      {"--vibration-pause", &EdgeParameters::chatter_vibration_pause, "the pause rule's level"},
      {"--vibration-growth", &EdgeParameters::chatter_vibration_growth,
       "what a rise is: q more than this times the revolution before"},
      {"--vibration-net", &EdgeParameters::chatter_vibration_net, "the net rule's floor"},
      {"--vibration-net-growth", &EdgeParameters::chatter_vibration_net_growth,
       "the net rule's growth over three revolutions"},
      {"--vibration-net-dip", &EdgeParameters::chatter_vibration_net_dip,
       "the net rule's largest fall on the way, a share"},
      {"--vibration-jump", &EdgeParameters::chatter_vibration_jump, "the jump rule's level"},
      {"--vibration-jump-growth", &EdgeParameters::chatter_vibration_jump_growth,
       "the jump rule's jump"},
      {"--vibration-jump-dip", &EdgeParameters::chatter_vibration_jump_dip,
       "the jump rule's largest fall after it, a share"},
      {"--vibration-steep", &EdgeParameters::chatter_vibration_steep, "the steep rule's level"},
      {"--vibration-steep-growth", &EdgeParameters::chatter_vibration_steep_growth,
       "the steep rule's growth in each of three rises"},
      {"--vibration-steep-from", &EdgeParameters::chatter_vibration_steep_from,
       "the least q a steep climb starts from"},
      {"--vibration-confirmed", &EdgeParameters::chatter_vibration_confirmed,
       "the steep climb's level where S confirms it"},
      {"--vibration-confirmed-growth", &EdgeParameters::chatter_vibration_confirmed_growth,
       "S's growth in each of the last two revolutions that confirms"},
      {"--vibration-level", &EdgeParameters::chatter_vibration_level,
       "q above this in 3 revolutions is chatter"},
      {"--vibration-held", &EdgeParameters::chatter_vibration_held,
       "q above this on average over 2 revolutions, the cutter wholly in the part, is chatter "
       "(1e9: off)"},
      {"--vibration-held-floor", &EdgeParameters::chatter_vibration_held_floor,
       "the held rule's floor: neither revolution below it"},
      {"--vibration-flip", &EdgeParameters::chatter_vibration_flip,
       "the estimate's period-doubling share above this in 2 revolutions is chatter"},
      {"--vibration-backup", &EdgeParameters::chatter_vibration_backup,
       "S above this in 3 revolutions is chatter (the backup; above 1, as shipped: off)"},
      {"--vibration-noise", &EdgeParameters::vibration_sensor_noise_rms_n,
       "the channel noise E takes out, N rms (the configuration's otherwise)"},
  };
  CLI::App app{
      "smc-bench-chatter-detector: module E on the simulated mill, one pass per cut at 0.1 "
      "mm/tooth programmed\n"
      "(the SMC II configuration). Each cut (speed x width x depth x runout x seed) runs with "
      "E's rules off,\n"
      "where the mill's own vibration labels it, then with E as it ships. Prints false "
      "detections, detections\n"
      "within 3 revolutions of the onset, the late and missed cuts, the label's margin, what "
      "the label's own\n"
      "rule makes of q read with an error (and which of E's own failures it makes too), and E's "
      "q\nagainst the mill's. Progress on stderr. Method: edge/CHATTER.md; figures: "
      "edge/README.md;\ndetails: the head of "
      "tests/bench/edge/chatter_study.cpp."};
  grid.add_options(app, ", one seed");
  std::string dump_path, samples_stem, plot_dir;
  app.add_flag("--force-only", force_only,
               "S alone, as on a sensor without the wideband F_y channel");
  app.add_flag("--no-regeneration", no_regeneration,
               "the mill cuts every chip at its nominal thickness: no cut can chatter, every "
               "onset and detection is a false one");
  app.add_flag("--twin-label", twin_label,
               "label each cut on what regeneration adds to its vibration: its labelling run's "
               "feed replayed on the same mill without regeneration, and the label's q of the "
               "difference (the mill's q in the figures below is that q too)");
  app.add_flag("--tick-label", tick_label,
               "with the wideband channel faster than the loop (as shipped): the label reads the "
               "mill's vibration at the sample period, not at the channel's rate");
  app.add_flag("--edge-knows-the-mill", edge_knows_the_mill,
               "with --mill-model: E undoes the mill's own structure, not the configuration's "
               "(as after a tap test on that machine); the critical depths still keep the "
               "configuration's model");
  app.add_flag("--edge-tool-modes-only", edge_tool_modes_only,
               "E undoes the tool's modes alone, as where the cell knows the machine's tool and "
               "not the part's own modes")
      ->excludes("--edge-knows-the-mill");
  app.add_option("--threshold", threshold_override,
                 "S's threshold (alone; 1 or more switches E's rules off in both runs, and each "
                 "cut runs once)")
      ->check(smc::bench::kPositive);
  app.add_option("--confirm", confirm_override, "S's revolutions in a row to confirm (alone)")
      ->check(smc::bench::kPositive);
  app.add_option("--channel-noise", channel_noise,
                 "the dynamometer's noise on every channel, N rms, and the noise E takes out "
                 "(the configuration's 2)")
      ->check(smc::bench::kNonNegative);
  app.add_option("--wide-cutoff", wide_cutoff,
                 "the wideband F_y channel's filter, Hz, and what E is told of it (the "
                 "configuration's 3500)")
      ->check(smc::bench::kPositive);
  app.add_option("--wide-order", wide_order,
                 "that filter's order, even, 2-8 (the configuration's 8)")
      ->check(CLI::Range(2, 8));
  app.add_option("--wide-samples", wide_samples,
                 "the wideband F_y channel's samples per sample period, and E's, whose rules "
                 "follow the channel's rate (the configuration's 5)")
      ->check(CLI::Range(1, 8));
  app.add_option("--sample-period", sample_period,
                 "the edge's sample period, s, and the channel's and the label's (0.0005)")
      ->check(smc::bench::kPositive);
  // E's rules follow the channel's rate: the set chosen at 10 kHz (the
  // configuration's) and the one chosen at the loop's 2 kHz.
  constexpr double kShippedChannelRateHz = 10000;  // 5 samples a 0.5 ms period
  EdgeParameters shipped;
  smc::supervision::set_vibration_rules_for_channel(shipped, kShippedChannelRateHz);
  const EdgeParameters at_loop;
  for (Knob& k : knobs) {
    char help[200];
    // The channel's noise comes from the configuration, the rules from
    // the channel's rate.
    if (k.field == &EdgeParameters::vibration_sensor_noise_rms_n) {
      std::snprintf(help, sizeof help, "%s", k.what);
    } else if (shipped.*k.field == at_loop.*k.field) {
      std::snprintf(help, sizeof help, "%s (shipped: %g)", k.what, shipped.*k.field);
    } else if (k.field == &EdgeParameters::chatter_vibration_held) {
      std::snprintf(help, sizeof help, "%s (shipped: %g at 10 kHz, off below it)", k.what,
                    shipped.*k.field);
    } else {
      std::snprintf(help, sizeof help, "%s (shipped: %g at 10 kHz, %g at 2 kHz)", k.what,
                    shipped.*k.field, at_loop.*k.field);
    }
    app.add_option(k.flag, k.value, help)->check(smc::bench::kNonNegative);
  }
  int flip_revolutions = 0;  // 0: shipped
  bool forget_across_steps = false;
  app.add_option("--vibration-flip-revolutions", flip_revolutions,
                 "the period-doubling rule's revolutions in a row (shipped: " +
                     std::to_string(shipped.chatter_vibration_flip_revolutions) + " at 10 kHz, " +
                     std::to_string(at_loop.chatter_vibration_flip_revolutions) + " at 2 kHz)")
      ->check(CLI::Range(1, 10));
  double rules_for_rate = 0;  // 0: the channel's own rate
  app.add_option("--rules-for-rate", rules_for_rate,
                 "E's rules are the set chosen for a wideband channel at this rate, Hz (from "
                 "4000: the set chosen at 10 kHz; below it the 2 kHz set), whatever the channel's "
                 "rate (default: the channel's own); the --vibration-* flags still apply")
      ->check(smc::bench::kPositive);
  app.add_flag("--vibration-forget-across-steps", forget_across_steps,
               "E's rules forget their last revolutions across one not judged for a step in the "
               "mean F_z (shipped: they keep them at 10 kHz, save across an aborted pass's ledge, "
               "and forget them at 2 kHz)");
  app.add_option("--dump", dump_path,
                 "CSV of every revolution of the labelling runs (E's q, S, the mill's q), to try "
                 "rules offline");
  app.add_option("--dump-samples", samples_stem,
                 "STEM.runs.csv, STEM.samples.bin, STEM.revs.bin: the labelling runs' samples, "
                 "to try statistics offline");
  app.add_option("--plot", plot_dir,
                 "write the study's figures into this directory: chatter-delay.svg, "
                 "chatter-margin.svg, chatter-estimate.svg, chatter-error.svg");
  CLI11_PARSE(app, argc, argv);
  grid.finish(app);
  if (grid.quick && app.count("--seeds") == 0) grid.seeds = 1;
  if (!plot_dir.empty()) {
    // Before the study's minutes, not after them.
    std::error_code ec;
    std::filesystem::create_directories(plot_dir, ec);
    if (ec) {
      std::fprintf(stderr, "--plot: %s: cannot create the directory: %s\n", plot_dir.c_str(),
                   ec.message().c_str());
      return 2;
    }
  }
  std::FILE* dump = nullptr;
  std::FILE* raw_runs = nullptr;
  std::FILE* raw_samples = nullptr;
  std::FILE* raw_revs = nullptr;
  uint64_t raw_sample_at = 0, raw_rev_at = 0;
  if (!samples_stem.empty()) {
    const std::string& stem = samples_stem;
    raw_runs = std::fopen((stem + ".runs.csv").c_str(), "w");
    raw_samples = std::fopen((stem + ".samples.bin").c_str(), "wb");
    raw_revs = std::fopen((stem + ".revs.bin").c_str(), "wb");
    if (raw_runs == nullptr || raw_samples == nullptr || raw_revs == nullptr) {
      std::perror((stem + ".{runs.csv,samples.bin,revs.bin}").c_str());
      return 2;
    }
    std::fprintf(raw_runs,
                 "run,rpm,width,runout,fraction,seed,onset_s,detected_s,sample_at,samples,rev_"
                 "at,revs\n");
  }
  if (!dump_path.empty()) {
    dump = std::fopen(dump_path.c_str(), "w");
    if (dump == nullptr) {
      std::perror(dump_path.c_str());
      return 2;
    }
    std::fprintf(dump,
                 "run,rpm,width,runout,fraction,seed,onset_s,t_s,statistic,vibration_ratio,"
                 "engagement,feed_per_tooth_mm,mill_q,flip\n");
  }
  const auto& speeds = grid.speeds;
  const auto& widths = grid.widths;
  const auto& fractions = grid.fractions;
  const auto& runouts = grid.runouts;
  const int seeds = grid.seeds;
  const bool verbose = grid.verbose;
  auto base = smc::documents::load_supervisor_config(std::string(SMC_SOURCE_DIR) +
                                                     "/edge/configs/smc2.textproto");
  smc::config::MillingModel plant;
  if (!grid.load_mill_model(plant)) return 2;
  const std::string& mill_model_file = grid.mill_model_file;
  if (edge_knows_the_mill && mill_model_file.empty()) {
    std::fprintf(stderr,
                 "--edge-knows-the-mill needs --mill-model FILE: without one the mill is the "
                 "configuration's model, whose structure E already undoes\n");
    return 2;
  }
  if (confirm_override > 0) {
    base.mutable_operation()->set_chatter_confirm_revolutions(
        static_cast<uint32_t>(confirm_override));
  }
  if (threshold_override > 0) base.mutable_operation()->set_chatter_threshold(threshold_override);
  if (no_regeneration) base.mutable_simulation()->set_no_regeneration(true);
  if (channel_noise >= 0) {
    base.mutable_simulation()->set_noise_rms_n(channel_noise);
    base.mutable_operation()->set_wideband_noise_rms_n(channel_noise);
  }
  if (wide_cutoff > 0) {
    base.mutable_simulation()->set_f_y_wide_cutoff_hz(wide_cutoff);
    base.mutable_operation()->set_wideband_cutoff_hz(wide_cutoff);
  }
  if (sample_period > 0) base.mutable_operation()->set_sample_period_s(sample_period);
  if (wide_samples > 0) {
    base.mutable_simulation()->set_f_y_wide_samples_per_tick(static_cast<uint32_t>(wide_samples));
    base.mutable_operation()->set_wideband_samples_per_tick(static_cast<uint32_t>(wide_samples));
  }
  if (wide_order > 0) {
    base.mutable_simulation()->set_f_y_wide_order(static_cast<uint32_t>(wide_order));
    base.mutable_operation()->set_wideband_filter_order(static_cast<uint32_t>(wide_order));
  }
  const double fpt = 0.1;
  // The study's rules on E's parameters (the configuration message does not
  // carry the vibration rules).
  auto tune = [&](EdgeParameters& ep) {
    if (force_only) ep.vibration_mode_count = 0;
    if (rules_for_rate > 0) smc::supervision::set_vibration_rules_for_channel(ep, rules_for_rate);
    for (const Knob& k : knobs) {
      if (k.value >= 0) ep.*k.field = k.value;
    }
    if (flip_revolutions > 0) ep.chatter_vibration_flip_revolutions = flip_revolutions;
    if (forget_across_steps) ep.chatter_vibration_keep_across_steps = false;
  };
  // E's rules off: the run that labels a cut.
  const bool e_muted = threshold_override >= 1;
  auto mute = [](EdgeParameters& ep) {
    ep.chatter_vibration_rise = ep.chatter_vibration_climb = ep.chatter_vibration_pause =
        ep.chatter_vibration_net = ep.chatter_vibration_jump = ep.chatter_vibration_steep =
            ep.chatter_vibration_confirmed = ep.chatter_vibration_level =
                ep.chatter_vibration_held = HUGE_VAL;
    ep.chatter_vibration_flip = 2;                           // a share: at most 1
    ep.chatter_vibration_backup = ep.chatter_threshold = 2;  // S is a share: at most 1
  };
  // One cut on the simulated mill, E listening or not.
  auto cut = [&](const smc::config::SupervisorConfig& raw,
                 const smc::config::MillingModel& mill_msg, bool listening, RunResult& run) {
    EdgeConfig cfg = edge_config_from_proto(raw);
    tune(cfg.params);
    if (!listening) mute(cfg.params);
    SimulatedMill mill(mill_msg, raw.simulation(), cfg.params.sample_period_s);
    EdgeCore core(cfg, mill);
    core.start();
    RunOptions opts;
    opts.max_time_s = 120;
    opts.keep_vibration_between_samples = !tick_label;
    run = run_virtual(core, opts);
    return summarize(core, run);
  };
  // The flags' configuration, checked once here: a bad value (a sample
  // period the control periods are no multiple of, say) is named, not thrown.
  EdgeParameters shown;
  try {
    shown = edge_config_from_proto(base).params;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "%s: the configuration these flags make is refused:\n%s\n", argv[0],
                 e.what());
    return 2;
  }
  tune(shown);
  const bool estimate = shown.vibration_mode_count > 0;
  // S's threshold in use: the backup's beside the estimate; with the backup
  // off (as shipped), the level it had until 2026-11-30, which the S_above
  // column and the margin still count against (no rule reads it).
  constexpr double kFormerBackup = 0.7;
  const double threshold = !estimate                             ? shown.chatter_threshold
                           : shown.chatter_vibration_backup <= 1 ? shown.chatter_vibration_backup
                                                                 : kFormerBackup;
  if (estimate) {
    char backup_text[96] = "; S, the non-harmonic share of F_z energy, is no backup";
    if (shown.chatter_vibration_backup <= 1) {
      std::snprintf(backup_text, sizeof backup_text,
                    "; or when S, the non-harmonic share of F_z energy, exceeds %.2f in 3",
                    shown.chatter_vibration_backup);
    }
    char held_text[128] = "";
    if (shown.chatter_vibration_held < EdgeParameters::kNoHeld) {
      std::snprintf(held_text, sizeof held_text,
                    ", or exceeds %.3f on average over 2, neither below %.3f, with the cutter "
                    "wholly in the part",
                    shown.chatter_vibration_held, shown.chatter_vibration_held_floor);
    }
    std::printf(
        "module E: the vibration estimated from the wideband F_y through %d y modes (the "
        "channel's %.0f Hz filter undone, %.1f N rms of its noise taken out), q = RMS(v_k - "
        "v_k-1) / RMS(v_k): chatter when q exceeds %.2f and rises, then rises again, or "
        "exceeds %.2f and rises three times in a row, or exceeds %.2f and rises, holds above "
        "it, then passes where it rose to (each rise by more than x%.2f), or exceeds %.3f in "
        "3 with the last x%.2f the one before them and none falling by more than %.0f%%, or "
        "jumps past %.2f by more than x%.2f and stays above it, falling by no more than "
        "%.0f%%, or rises three times in a row by more than x%.2f each from %.2f to past "
        "%.2f (to past %.2f where S, below, rose by more than x%.2f in each of the last two), "
        "or exceeds %.2f in 3%s; or when the estimate's share at the spindle orders halfway "
        "between tooth harmonics (a period doubling) exceeds %.2f in %d%s%s",
        shown.vibration_mode_count, shown.vibration_sensor_cutoff_hz,
        shown.vibration_sensor_noise_rms_n, shown.chatter_vibration_rise,
        shown.chatter_vibration_climb, shown.chatter_vibration_pause,
        shown.chatter_vibration_growth, shown.chatter_vibration_net,
        shown.chatter_vibration_net_growth, 100 * shown.chatter_vibration_net_dip,
        shown.chatter_vibration_jump, shown.chatter_vibration_jump_growth,
        100 * shown.chatter_vibration_jump_dip, shown.chatter_vibration_steep_growth,
        shown.chatter_vibration_steep_from, shown.chatter_vibration_steep,
        shown.chatter_vibration_confirmed, shown.chatter_vibration_confirmed_growth,
        shown.chatter_vibration_level, held_text, shown.chatter_vibration_flip,
        shown.chatter_vibration_flip_revolutions, backup_text,
        shown.chatter_vibration_keep_across_steps
            ? " (q's rules keep their history across a step in the mean F_z, save where the "
              "cutter crosses an aborted pass's ledge)"
            : "");
  } else {
    std::printf(
        "module E: threshold %.2f on S, the non-harmonic share of F_z energy, %d revolutions "
        "to confirm",
        shown.chatter_threshold, shown.chatter_confirm_revolutions);
  }
  std::printf(
      "; band %.0f-%.0f Hz, guard +-%.0f Hz, noise %.1f N rms, a sample every %.2f ms (the "
      "wideband channel's every %.3f ms); "
      "programmed %.2f mm/tooth, %d seeds; the mill: %s%s%s; labelled on %s, read every "
      "%.3f ms\n\n",
      base.operation().chatter_band_low_hz(), base.operation().chatter_band_high_hz(),
      base.operation().harmonic_guard_hz(), base.simulation().noise_rms_n(),
      1000 * shown.sample_period_s, 1000 * shown.sample_period_s / shown.vibration_samples_per_tick,
      fpt, seeds, mill_model_file.empty() ? "the configuration's model" : mill_model_file.c_str(),
      edge_knows_the_mill    ? ", whose structure E undoes"
      : edge_tool_modes_only ? " (E undoes the tool's modes alone)"
                             : "",
      no_regeneration ? ", without regeneration (no cut can chatter: every onset the label "
                        "finds is the forced response's)"
                      : "",
      twin_label ? "what regeneration adds to the vibration (the cut replayed without it)"
                 : "the mill's vibration",
      1000 * shown.sample_period_s /
          (twin_label || tick_label ? 1 : shown.vibration_samples_per_tick));
  std::printf("%6s %6s %6s %8s %6s %9s %8s %8s %8s %8s %8s %9s %8s %10s\n", "rpm", "width",
              "runout", "crit_mm", "runs", "stable", "revs", "S_above", "false", "max_S", "max_q",
              "unstable", "within3", "delay_rev");
  std::vector<Cell> cells;
  int run_id = 0;
  Cell all;
  // The label's own margin (the mill's q, revolution by revolution, from the
  // labelling run): the largest onset level of a stable cut (below the
  // onset's threshold, or it would not be stable) and the smallest of an
  // unstable cut's onset; and E's estimate of q against the mill's own, on
  // the revolutions near the threshold, by speed.
  double stable_level = 0, unstable_level = HUGE_VAL;
  // The same for the period doubling's share (the onsets it called alone,
  // how many the rule on q never called, and how many revolutions earlier
  // than q's it was where q's came too), and E's share against the mill's
  // on revolutions where the mill's is past 0.3, and E's largest in stable
  // cuts (the least of three revolutions in a row, as its rule counts).
  double stable_flip = 0, unstable_flip = HUGE_VAL, stable_e_flip = 0;
  int flip_onsets = 0, flip_only = 0;
  std::vector<double> flip_ahead, flip_error;
  std::vector<LateCut> late;
  std::vector<EarlyCut> early;
  std::map<double, std::vector<double>> estimate_error;  // rpm -> q_E / q
  // E's q where the mill's is below kStillQ (a cut that repeats itself):
  // what the channel's noise alone makes of it, by speed.
  constexpr double kStillQ = 0.02;
  std::map<double, std::vector<double>> still;  // rpm -> q_E
  std::vector<double> mill_q;                   // per labelled revolution
  std::vector<LabelledCut> labelled_cuts;
  smc::bench::ChatterStudyFigures figures;  // --plot's
  const double still_period_s = base.operation().slow_period_s();
  for (double rpm : speeds) {
    for (double width : widths) {
      auto model_msg = base.milling_model();
      model_msg.mutable_workpiece()->set_width_mm(width);
      const auto model = smc::machining::from_proto(model_msg, "study");
      smc::machining::TdsSearchOptions so;
      so.relative_tolerance = 1e-2;
      so.max_depth_mm = 20;
      const auto crit = smc::machining::critical_depth_tds(model, rpm, fpt, so);
      const auto plain_msg = model_msg;
      for (double runout : runouts) {
        model_msg = plain_msg;
        if (runout > 0) {
          for (const double r : smc::machining::eccentric_runout_um(
                   static_cast<int>(model_msg.cutter().teeth()), runout)) {
            model_msg.mutable_cutter()->add_radial_runout_um(r);
          }
        }
        Cell c;
        c.rpm = rpm;
        c.width = width;
        c.runout = runout;
        for (double fraction : fractions) {
          const double depth = fraction * crit.critical_depth_mm;
          for (int seed = 1; seed <= seeds; ++seed) {
            std::fprintf(stderr,
                         "\r%4.0f rpm, %2.0f mm wide, runout %2.0f um: depth %.2f mm, seed %d   ",
                         rpm, width, runout, depth, seed);
            auto raw = base;
            *raw.mutable_milling_model() = model_msg;
            auto* pass = raw.mutable_program()->mutable_passes(0);
            pass->set_depth_mm(depth);
            pass->set_spindle_rpm(rpm);
            pass->set_feedrate_mm_s(fpt * raw.operation().teeth() * rpm / 60.0);
            raw.mutable_program()->set_total_depth_mm(depth);
            raw.mutable_simulation()->set_seed(static_cast<uint64_t>(seed));
            // The mill that cuts: the configuration's model, or --mill-model's
            // with this cutter (runout) and part (width).
            auto mill_msg = raw.milling_model();
            if (!mill_model_file.empty()) use_plant_model(mill_msg, plant);
            if (edge_knows_the_mill) {
              *raw.mutable_milling_model()->mutable_structure() = mill_msg.structure();
            }
            if (edge_tool_modes_only) {
              raw.mutable_milling_model()->mutable_structure()->clear_part_x();
              raw.mutable_milling_model()->mutable_structure()->clear_part_y();
            }
            // The cut twice: with E's rules off, which labels it (the onset
            // from the vibration, nothing reacting to it), then with E
            // listening, whose first detection is what it decides before
            // anything reacts (its state up to then does not depend on the
            // reaction). Labelled from the listening run instead, a
            // detection would make its own onset: the summary's onset takes
            // a rising revolution followed by a hold as the start of chatter.
            RunResult labelled, heard;
            const auto label = cut(raw, mill_msg, false, labelled);
            const auto s = e_muted ? label : cut(raw, mill_msg, true, heard);
            const RunResult& run = e_muted ? labelled : heard;
            // --twin-label: the same cut on the mill without regeneration,
            // fed as the labelling run was, and the label on what
            // regeneration adds to the vibration.
            std::vector<double> forced;
            if (twin_label) {
              auto twin_sim = raw.simulation();
              twin_sim.set_no_regeneration(true);
              const EdgeConfig twin_cfg = edge_config_from_proto(raw);
              SimulatedMill twin(mill_msg, twin_sim, twin_cfg.params.sample_period_s);
              twin.load(twin_cfg.program);
              forced = forced_vibration(labelled, twin);
            }
            const auto changes = vibration_change(labelled, still_period_s,
                                                  static_cast<int>(raw.operation().teeth()),
                                                  twin_label ? &forced : nullptr);
            const double onset =
                twin_label ? first_onset_s(labelled, changes) : label.chatter_onset_s();
            const double first_detection = s.chatter_detected_s();
            bool premature = false;             // before the onset: a false detection
            Outcome outcome = Outcome::kQuiet;  // E's first decision, as the tables count it
            ++run_id;
            {
              LabelledCut& kept = labelled_cuts.emplace_back();
              kept.rpm = rpm;
              kept.width = width;
              kept.runout = runout;
              kept.fraction = fraction;
              kept.seed = seed;
              kept.onset_s = onset;
              kept.changes = changes;
              for (const auto& change : changes) {
                kept.end_s.push_back(labelled.samples[change.end_sample - 1].t_s);
              }
              // The cut's level in q and in the period doubling's share:
              // a stable cut's largest, an unstable cut's at its onset (by
              // flip: the onset was the period doubling's alone).
              double cut_level = 0, cut_flip = 0;
              bool by_flip = false;
              for (const auto& change : changes) {
                if (onset >= 0 && change.onset()) {
                  cut_level = change.onset_level;
                  cut_flip = change.flip_onset_level;
                  by_flip = !(change.onset_level > kChatterOnsetQ);
                  break;
                }
                cut_level = std::max(cut_level, change.onset_level);
                cut_flip = std::max(cut_flip, change.flip_onset_level);
              }
              if (onset < 0) {
                stable_level = std::max(stable_level, cut_level);
                stable_flip = std::max(stable_flip, cut_flip);
              } else if (by_flip) {
                ++flip_onsets;
                unstable_flip = std::min(unstable_flip, cut_flip);
                // The onset the rule on q alone would have found, if any.
                size_t q_at = 0, flip_at = 0;
                while (flip_at < changes.size() && !changes[flip_at].onset()) ++flip_at;
                while (q_at < changes.size() && !(changes[q_at].onset_level > kChatterOnsetQ)) {
                  ++q_at;
                }
                if (q_at == changes.size()) {
                  ++flip_only;
                } else {
                  flip_ahead.push_back(static_cast<double>(q_at - flip_at));
                }
              } else {
                unstable_level = std::min(unstable_level, cut_level);
              }
              if (onset >= 0) {
                const double delay =
                    first_detection >= 0 ? (first_detection - onset) * rpm / 60.0 : -1;
                if (first_detection >= 0 && delay < 0) {
                  EarlyCut ec{rpm, width, runout, fraction, seed, delay, {}, 0};
                  // The revolution that ends where E decided (or the last before).
                  size_t at = 0;
                  while (at + 1 < changes.size() &&
                         labelled.samples[changes[at + 1].end_sample - 1].t_s <=
                             first_detection + 1e-9) {
                    ++at;
                  }
                  for (size_t r = at >= 3 ? at - 3 : 0; r < changes.size() && r <= at + 1; ++r) {
                    ec.q.push_back(changes[r].comparable ? changes[r].q : -1);
                  }
                  for (size_t r = at; r < changes.size(); ++r) {
                    if (labelled.samples[changes[r].end_sample - 1].t_s > onset + 1e-9) break;
                    if (changes[r].comparable)
                      ec.most_before_onset = std::max(ec.most_before_onset, changes[r].q);
                  }
                  ec.premature = premature = !passed_onset_level(changes, at);
                  early.push_back(ec);
                }
                if (delay < 0 ? first_detection < 0 : delay > 3.0) {
                  LateCut lc{rpm, width, runout, fraction, seed, delay, {}, 0, -1, by_flip};
                  size_t at = 0;
                  while (at < changes.size() && !changes[at].onset()) ++at;
                  // The witness that called the onset: q, or the period
                  // doubling's share.
                  auto value = [&](const RevolutionChange& x) { return by_flip ? x.flip : x.q; };
                  const double level = by_flip ? kChatterOnsetFlip : kChatterOnsetQ;
                  for (size_t r = at > 0 ? at - 1 : 0; r < changes.size() && r <= at + 5; ++r) {
                    lc.q.push_back(changes[r].comparable ? value(changes[r]) : -1);
                  }
                  size_t r = at;
                  while (r < changes.size() && changes[r].comparable && value(changes[r]) > level) {
                    ++lc.above;
                    ++r;
                  }
                  for (; r < changes.size(); ++r) {
                    if (changes[r].comparable)
                      lc.later_most = std::max(lc.later_most, value(changes[r]));
                  }
                  late.push_back(lc);
                }
              }
              {
                auto& fc = figures.cuts.emplace_back();
                fc.rpm = rpm;
                fc.width = width;
                fc.runout = runout;
                fc.unstable = onset >= 0;
                fc.premature = premature;
                fc.detected = first_detection >= 0 && !premature;
                fc.delay_revs = first_detection >= 0 ? (first_detection - onset) * rpm / 60.0
                                                     : std::numeric_limits<double>::quiet_NaN();
                fc.level = cut_level;
                fc.by_flip = by_flip;
                if (!fc.unstable) {
                  outcome = first_detection >= 0 ? Outcome::kFalse : Outcome::kQuiet;
                } else if (premature) {
                  outcome = Outcome::kFalse;
                } else if (first_detection < 0) {
                  outcome = Outcome::kMissed;
                } else {
                  outcome = fc.delay_revs <= 3.0 ? Outcome::kWithin3 : Outcome::kLate;
                }
                kept.e = outcome;
              }
              // E's revolutions end on the trace's (both count the same
              // clock): pair each with the trace's that ends there, for the
              // mill's own q (-1: none there, or not comparable).
              const double dt = labelled.samples.size() > 1
                                    ? labelled.samples[1].t_s - labelled.samples[0].t_s
                                    : 0;
              mill_q.assign(labelled.revolutions.size(), -1.0);
              size_t at = 0;
              for (size_t i = 0; i < labelled.revolutions.size(); ++i) {
                const auto& r = labelled.revolutions[i];
                while (at < changes.size() &&
                       labelled.samples[changes[at].end_sample - 1].t_s < r.t_s - 0.5 * dt) {
                  ++at;
                }
                if (at == changes.size()) break;
                const auto& change = changes[at];
                if (std::fabs(labelled.samples[change.end_sample - 1].t_s - r.t_s) > 0.5 * dt ||
                    !change.comparable) {
                  continue;
                }
                mill_q[i] = change.q;
                if (r.chatter_vibration_flip > 0 && change.flip >= 0.3) {
                  flip_error.push_back(r.chatter_vibration_flip / change.flip);
                }
                if (!plot_dir.empty() && r.chatter_vibration_ratio > 0) {
                  figures.q_pairs.push_back({rpm, change.q, r.chatter_vibration_ratio});
                }
                if (r.chatter_vibration_ratio > 0 && change.q >= 0.1 && change.q <= 0.3) {
                  estimate_error[rpm].push_back(r.chatter_vibration_ratio / change.q);
                }
                // Before the onset only: chatter's own start is not still.
                if (change.q < kStillQ && (onset < 0 || r.t_s < onset) &&
                    (r.active & bit(ModuleId::E)) != 0 && r.contact) {
                  still[rpm].push_back(r.chatter_vibration_ratio);
                }
              }
            }
            if (onset < 0) {
              // E's period-doubling share in a stable cut, as its rule
              // counts it: the least of as many judged revolutions in a
              // row as the rule asks for.
              const auto in_a_row =
                  static_cast<size_t>(std::max(1, shown.chatter_vibration_flip_revolutions));
              std::vector<double> judged;  // the shares of the judged revolutions in a row
              for (const auto& r : labelled.revolutions) {
                const double f = r.chatter_vibration_flip;
                if (!(f > 0)) {
                  judged.clear();
                  continue;
                }
                judged.push_back(f);
                if (judged.size() >= in_a_row) {
                  stable_e_flip = std::max(
                      stable_e_flip,
                      *std::min_element(judged.end() - static_cast<long>(in_a_row), judged.end()));
                }
              }
            }
            if (dump != nullptr) {
              for (size_t i = 0; i < labelled.revolutions.size(); ++i) {
                const auto& r = labelled.revolutions[i];
                if ((r.active & bit(ModuleId::E)) == 0 || !r.contact) continue;
                std::fprintf(dump,
                             "%d,%.0f,%.0f,%.0f,%.2f,%d,%.4f,%.4f,%.5f,%.5f,%.4f,%.5f,%.5f,%.5f\n",
                             run_id, rpm, width, runout, fraction, seed, onset, r.t_s,
                             r.chatter_ratio, r.chatter_vibration_ratio, r.engagement_min,
                             r.feed_per_tooth_mm, mill_q[i], r.chatter_vibration_flip);
              }
            }
            if (raw_runs != nullptr) {
              uint64_t ns = 0, nr = 0;
              for (const auto& t : labelled.samples) {
                const float v[4] = {
                    static_cast<float>(t.f_z_n), static_cast<float>(t.feedrate_mm_s),
                    static_cast<float>(t.vibration_y_mm), static_cast<float>(t.f_y_wide_n)};
                const uint8_t flags = (t.contact ? 1 : 0) |
                                      ((t.active & bit(ModuleId::E)) ? 2 : 0) | (t.in_pass ? 4 : 0);
                std::fwrite(&t.t_s, 8, 1, raw_samples);
                std::fwrite(v, 4, 4, raw_samples);
                std::fwrite(&flags, 1, 1, raw_samples);
                ++ns;
              }
              for (const auto& r : labelled.revolutions) {
                const float v[2] = {static_cast<float>(r.chatter_ratio),
                                    static_cast<float>(r.feed_per_tooth_mm)};
                const uint8_t flags = (r.contact ? 1 : 0) | ((r.active & bit(ModuleId::E)) ? 2 : 0);
                std::fwrite(&r.t_s, 8, 1, raw_revs);
                std::fwrite(v, 4, 2, raw_revs);
                std::fwrite(&flags, 1, 1, raw_revs);
                ++nr;
              }
              std::fprintf(raw_runs, "%d,%.0f,%.0f,%.0f,%.2f,%d,%.6f,%.6f,%llu,%llu,%llu,%llu\n",
                           run_id, rpm, width, runout, fraction, seed, onset, first_detection,
                           static_cast<unsigned long long>(raw_sample_at),
                           static_cast<unsigned long long>(ns),
                           static_cast<unsigned long long>(raw_rev_at),
                           static_cast<unsigned long long>(nr));
              std::fflush(raw_runs);
              raw_sample_at += ns;
              raw_rev_at += nr;
            }
            uint64_t revs = 0, exceed = 0;
            double max_ratio = 0, max_q = 0;
            for (const auto& r : run.revolutions) {
              if ((r.active & bit(ModuleId::E)) == 0 || !r.contact) continue;
              if (first_detection >= 0 && r.t_s > first_detection) break;
              ++revs;
              if (verbose && (r.chatter_ratio > 0.5 * threshold ||
                              r.chatter_vibration_ratio > 0.5 * shown.chatter_vibration_rise)) {
                std::fprintf(stderr, "    t %.3f x %.1f engagement %.2f F_Y %.0f S %.3f q %.3f\n",
                             r.t_s, r.x_mm, r.engagement_min, r.f_y_peak_n, r.chatter_ratio,
                             r.chatter_vibration_ratio);
              }
              if (r.chatter_ratio > threshold) ++exceed;
              max_ratio = std::max(max_ratio, r.chatter_ratio);
              max_q = std::max(max_q, r.chatter_vibration_ratio);
            }
            ++c.runs;
            if (verbose) {
              std::fprintf(stderr,
                           "\n  depth %.2f seed %d: onset %.3f s, detected %.3f s, %llu revs, max "
                           "statistic %.3f, %d passes\n",
                           depth, seed, onset, first_detection,
                           static_cast<unsigned long long>(revs), max_ratio, s.passes_size());
            }
            if (onset < 0) {
              ++c.stable_runs;
              c.stable_revs += revs;
              c.exceed += exceed;
              c.stable_max = std::max(c.stable_max, max_ratio);
              c.stable_max_q = std::max(c.stable_max_q, max_q);
              c.false_detections += outcome == Outcome::kFalse ? 1 : 0;
            } else {
              ++c.unstable_runs;
              if (outcome == Outcome::kFalse) {
                ++c.false_detections;
                ++c.premature;
              } else if (outcome != Outcome::kMissed) {
                ++c.detected;
                const double delay = (first_detection - onset) * rpm / 60.0;
                c.worst_delay_revs = std::max(c.worst_delay_revs, delay);
                c.within3 += outcome == Outcome::kWithin3 ? 1 : 0;
                c.unstable_min_peak = std::min(c.unstable_min_peak, max_ratio);
              }
            }
          }
        }
        std::printf(
            "%6.0f %6.0f %6.0f %8.2f %6d %9d %8llu %8llu %8d %8.3f %8.3f %5d/%-3d %8d %10.1f\n",
            rpm, width, runout, crit.critical_depth_mm, c.runs, c.stable_runs,
            static_cast<unsigned long long>(c.stable_revs),
            static_cast<unsigned long long>(c.exceed), c.false_detections, c.stable_max,
            c.stable_max_q, c.detected, c.unstable_runs, c.within3, c.worst_delay_revs);
        std::fflush(stdout);
        all.runs += c.runs;
        all.stable_runs += c.stable_runs;
        all.unstable_runs += c.unstable_runs;
        all.detected += c.detected;
        all.false_detections += c.false_detections;
        all.premature += c.premature;
        all.stable_revs += c.stable_revs;
        all.exceed += c.exceed;
        all.stable_max = std::max(all.stable_max, c.stable_max);
        all.stable_max_q = std::max(all.stable_max_q, c.stable_max_q);
        all.within3 += c.within3;
        all.worst_delay_revs = std::max(all.worst_delay_revs, c.worst_delay_revs);
        if (c.detected > 0)
          all.unstable_min_peak = std::min(all.unstable_min_peak, c.unstable_min_peak);
        cells.push_back(c);
      }
    }
  }
  std::fprintf(stderr, "\n");
  std::printf(
      "\nstable cuts: %d runs, %llu revolutions in the cut, %llu with S above %.2f, %d confirmed "
      "false detections (%d of them before an unstable cut's onset, the mill's q below %.2f); "
      "largest S %.3f (margin: threshold / largest = %.2f); largest q %.3f\n",
      all.stable_runs, static_cast<unsigned long long>(all.stable_revs),
      static_cast<unsigned long long>(all.exceed), threshold, all.false_detections, all.premature,
      kChatterOnsetQ, all.stable_max, all.stable_max > 0 ? threshold / all.stable_max : 0.0,
      all.stable_max_q);
  std::printf(
      "unstable cuts: %d runs, %d detected, %d within 3 revolutions of the onset; worst delay "
      "%.1f revolutions; smallest peak S of a detected cut %.3f\n",
      all.unstable_runs, all.detected, all.within3, all.worst_delay_revs,
      all.detected > 0 ? all.unstable_min_peak : 0.0);
  const bool pass =
      all.false_detections == 0 && all.detected == all.unstable_runs && all.worst_delay_revs <= 3.0;
  std::printf("goal (0 false detections, every unstable cut within 3 revolutions): %s\n",
              pass ? "met" : "NOT met");
  if (!late.empty()) {
    std::printf(
        "\nunstable cuts caught late or missed: the mill's own q from the revolution before the "
        "onset (- not comparable), the revolutions from the onset on above %.2f, and the largest "
        "q after them to the end of the pass (- none: it lasted to the end); where the onset was "
        "a period doubling's (flip), its share instead of q, above %.2f\n%6s %6s %6s %8s %4s "
        "%7s  %-47s %5s %6s\n",
        kChatterOnsetQ, kChatterOnsetFlip, "rpm", "width", "runout", "fraction", "seed", "delay",
        "mill's q", "above", "later");
    for (const auto& lc : late) {
      const std::string qs = q_list(lc.q);
      char delay[16];
      if (lc.delay_revs < 0) {
        std::snprintf(delay, sizeof delay, "%s", "missed");
      } else {
        std::snprintf(delay, sizeof delay, "%.0f", lc.delay_revs);
      }
      // Nothing after the excursion: it lasted to the end of the pass.
      char later[16];
      if (lc.later_most < 0) {
        std::snprintf(later, sizeof later, "%s", "-");
      } else {
        std::snprintf(later, sizeof later, "%.3f", lc.later_most);
      }
      std::printf("%6.0f %6.0f %6.0f %8.2f %4d %7s  %-47s %5d %6s%s\n", lc.rpm, lc.width, lc.runout,
                  lc.fraction, lc.seed, delay, qs.c_str(), lc.above, later,
                  lc.by_flip ? "  flip" : "");
    }
  }
  if (!early.empty()) {
    std::printf(
        "\nunstable cuts E detected before the label's onset: the mill's own q from three "
        "revolutions before E's detection to the one after (the fourth is E's; - not "
        "comparable), its largest q from there to the onset, and how the detection is counted "
        "(chatter the label had not called, within 3 revolutions, where the mill's q passed "
        "%.2f in E's revolution or the three before; a false detection where it did not)\n%6s "
        "%6s %6s %8s %4s %7s  %-35s %8s  %s\n",
        kChatterOnsetQ, "rpm", "width", "runout", "fraction", "seed", "delay", "mill's q", "most",
        "counted");
    for (const auto& ec : early) {
      const std::string qs = q_list(ec.q);
      std::printf("%6.0f %6.0f %6.0f %8.2f %4d %7.0f  %-35s %8.3f  %s\n", ec.rpm, ec.width,
                  ec.runout, ec.fraction, ec.seed, ec.delay_revs, qs.c_str(), ec.most_before_onset,
                  ec.premature ? "false" : "within 3");
    }
  }
  std::printf(
      "\nthe label's own margin, in the mill's q: the largest onset level of a stable cut %.4f, "
      "the smallest of an unstable cut's onset %.4f (threshold %.2f)\n",
      stable_level, unstable_level < HUGE_VAL ? unstable_level : 0.0, kChatterOnsetQ);
  if (estimate) {
    std::printf(
        "the label's period doubling (the mill's vibration at the spindle orders halfway between "
        "tooth harmonics, its share of the AC energy held over three revolutions): %d onsets "
        "called by it alone, %d of them never by the rule on q",
        flip_onsets, flip_only);
    if (!flip_ahead.empty()) {
      std::sort(flip_ahead.begin(), flip_ahead.end());
      std::printf(", the others %.0f-%.0f revolutions (median %.0f) before q's", flip_ahead.front(),
                  flip_ahead.back(), flip_ahead[flip_ahead.size() / 2]);
    }
    std::printf(
        "; its margin: the largest level of a stable cut %.4f, the smallest of such an onset "
        "%.4f (threshold %.2f)\n",
        stable_flip, unstable_flip < HUGE_VAL ? unstable_flip : 0.0, kChatterOnsetFlip);
    std::printf(
        "E's period-doubling share: in stable cuts at most %.4f (the least of %d in a row; "
        "E's rule %.2f in %d)",
        stable_e_flip, shown.chatter_vibration_flip_revolutions, shown.chatter_vibration_flip,
        shown.chatter_vibration_flip_revolutions);
    if (!flip_error.empty()) {
      std::sort(flip_error.begin(), flip_error.end());
      auto pct = [&](double f) {
        return flip_error[static_cast<size_t>(f * static_cast<double>(flip_error.size() - 1) +
                                              0.5)];
      };
      std::printf(
          "; against the mill's where the mill's is 0.3 or more (%zu revolutions): p5 "
          "%.3f, median %.3f, p95 %.3f",
          flip_error.size(), pct(0.05), pct(0.5), pct(0.95));
    }
    std::printf("\n");
  }
  {
    // How much the label's decision depends on q's last per cent: its own
    // rule, run as a detector on the mill's q read with an error.
    constexpr unsigned kDraws = 5;
    int unstable_cuts = 0;
    for (const auto& kept : labelled_cuts) unstable_cuts += kept.onset_s >= 0 ? 1 : 0;
    std::printf(
        "the label's own rule run as a detector on the mill's q read with a random error "
        "(Gaussian, relative, drawn per revolution; the fewest-most over %u draws) against the "
        "label on the exact q:\n%8s %15s %15s %15s\n",
        kDraws, "error", "false", "detected", "within3");
    for (const double sigma : {0.0, 0.0025, 0.01, 0.02, 0.05, 0.10}) {
      RuleOnError lo{1 << 30, 1 << 30, 1 << 30}, hi{-1, -1, -1};
      smc::bench::ChatterStudyFigures::ErrorRow row;
      row.sigma = sigma;
      const unsigned draws = sigma > 0 ? kDraws : 1;
      for (unsigned d = 0; d < draws; ++d) {
        const RuleOnError r = label_rule_on_error(labelled_cuts, sigma, d + 1);
        row.false_mean += static_cast<double>(r.false_detections) / draws;
        row.late_mean += static_cast<double>(unstable_cuts - r.within3) / draws;
        lo = {std::min(lo.false_detections, r.false_detections), std::min(lo.detected, r.detected),
              std::min(lo.within3, r.within3)};
        hi = {std::max(hi.false_detections, r.false_detections), std::max(hi.detected, r.detected),
              std::max(hi.within3, r.within3)};
      }
      row.false_lo = lo.false_detections;
      row.false_hi = hi.false_detections;
      row.late_lo = unstable_cuts - hi.within3;
      row.late_hi = unstable_cuts - lo.within3;
      figures.error_rows.push_back(row);
      char cols[3][32];
      const int lows[3] = {lo.false_detections, lo.detected, lo.within3};
      const int highs[3] = {hi.false_detections, hi.detected, hi.within3};
      for (int k = 0; k < 3; ++k) {
        if (lows[k] == highs[k]) {
          std::snprintf(cols[k], sizeof cols[k], "%d", lows[k]);
        } else {
          std::snprintf(cols[k], sizeof cols[k], "%d-%d", lows[k], highs[k]);
        }
      }
      std::printf("%7.2f%% %15s %11s/%-3d %15s\n", 100 * sigma, cols[0], cols[1], unstable_cuts,
                  cols[2]);
    }
    // E's own failures against the same: is each a decision the label's
    // rule makes too, on this cut's q read with a small error? Then no
    // reading of q that close to the mill's can be sure to avoid it.
    constexpr unsigned kCutDraws = 100, kCutSame = 5;  // one draw in 20 at least
    constexpr double kSigmas[] = {0.005, 0.01, 0.02};
    constexpr double kListedSigma = 0.01;  // the cuts it does not explain are listed
    std::vector<const LabelledCut*> failures;
    for (const auto& kept : labelled_cuts) {
      if (failed(kept.e)) failures.push_back(&kept);
    }
    if (!failures.empty()) {
      std::printf(
          "E's false detections and late or missed cuts that the label's own rule makes too on "
          "that cut's q read with a small error (Gaussian, relative, per revolution; the same kind "
          "of failure in at least %u of %u draws):",
          kCutSame, kCutDraws);
      std::vector<const LabelledCut*> unexplained;
      for (const double sigma : kSigmas) {
        int false_all = 0, false_same = 0, late_all = 0, late_same = 0;
        std::vector<RevolutionChange> read;
        for (size_t i = 0; i < failures.size(); ++i) {
          const LabelledCut& failure = *failures[i];
          std::mt19937_64 rng(1000003u * (i + 1));
          std::normal_distribution<double> error(0.0, sigma);
          unsigned times = 0;
          for (unsigned d = 0; d < kCutDraws; ++d) {
            times +=
                same_failure(failure.e, label_rule_outcome(failure, rng, error, read)) ? 1u : 0u;
          }
          const bool same = times >= kCutSame;
          const bool is_false = failure.e == Outcome::kFalse;
          (is_false ? false_all : late_all) += 1;
          (is_false ? false_same : late_same) += same ? 1 : 0;
          if (!same && sigma == kListedSigma) unexplained.push_back(&failure);
        }
        std::printf("%s at %.1f %%, %d of %d false detections and %d of %d late or missed",
                    sigma == kSigmas[0] ? "" : ";", 100 * sigma, false_same, false_all, late_same,
                    late_all);
      }
      std::printf("\n");
      for (const LabelledCut* u : unexplained) {
        std::printf("  not so at %.1f %%: %.0f rpm, %.0f mm, %.0f um, %.2f x, seed %d (%s)\n",
                    100 * kListedSigma, u->rpm, u->width, u->runout, u->fraction, u->seed,
                    u->e == Outcome::kFalse  ? "false detection"
                    : u->e == Outcome::kLate ? "late"
                                             : "missed");
      }
    }
  }
  if (estimate && !estimate_error.empty()) {
    std::printf(
        "E's q against the mill's, comparable revolutions with the mill's q in 0.10-0.30 "
        "(labelling runs):\n%6s %9s %8s %8s %8s\n",
        "rpm", "revs", "p5", "median", "p95");
    for (auto& [speed, e] : estimate_error) {
      std::sort(e.begin(), e.end());
      auto pct = [&](double f) {
        return e[static_cast<size_t>(f * static_cast<double>(e.size() - 1) + 0.5)];
      };
      std::printf("%6.0f %9zu %8.3f %8.3f %8.3f\n", speed, e.size(), pct(0.05), pct(0.5),
                  pct(0.95));
    }
  }
  if (estimate && !still.empty()) {
    std::printf(
        "E's q where the mill's q is below %.2f (the cut repeats itself; labelling runs, before "
        "any onset, E active in the cut): what the channel's noise makes of it\n%6s %9s %9s %9s "
        "%8s\n",
        kStillQ, "rpm", "revs", ">0.10", ">0.15", "largest");
    for (const auto& [speed, e] : still) {
      const auto above = [&](double x) {
        return std::count_if(e.begin(), e.end(), [x](double v) { return v > x; });
      };
      std::printf("%6.0f %9zu %9td %9td %8.3f\n", speed, e.size(), above(0.10), above(0.15),
                  *std::max_element(e.begin(), e.end()));
    }
  }
  if (!plot_dir.empty()) {
    figures.unstable = all.unstable_runs;
    figures.e_false = all.false_detections;
    figures.e_late = all.unstable_runs - all.within3;
    figures.onset_q = kChatterOnsetQ;
    char what[200];
    std::snprintf(what, sizeof what, "%s, %d seed%s, runouts %s um, depths %s x critical",
                  mill_model_file.empty() ? "the configuration's mill" : mill_model_file.c_str(),
                  seeds, seeds == 1 ? "" : "s", smc::bench::joined(runouts).c_str(),
                  smc::bench::joined(fractions).c_str());
    figures.subtitle = what;
    try {
      std::string written;
      for (const auto& path : smc::bench::write_chatter_figures(plot_dir, figures)) {
        written += " " + path.string();
      }
      std::printf("\nfigures:%s\n", written.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "--plot: %s\n", e.what());
      return 2;
    }
  }
  if (dump != nullptr) std::fclose(dump);
  if (raw_runs != nullptr) {
    std::fclose(raw_runs);
    std::fclose(raw_samples);
    std::fclose(raw_revs);
  }
  return 0;
}
