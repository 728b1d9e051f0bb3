#pragma once
// The grid of cuts the edge studies sweep (chatter detector, tool-breakage
// detector), and the command-line options they share.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc_config.pb.h"

namespace smc::bench {

// A number above 0 (kPositive) or at least 0 (kNonNegative), with a message
// that says which (CLI11's own ranges print the largest double).
inline CLI::Validator number_check(bool zero_allowed) {
  return CLI::Validator(
      [zero_allowed](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(x)) {
          return "'" + text + "' is not a number";
        }
        if (zero_allowed ? x >= 0 : x > 0) return {};
        return text + (zero_allowed ? " is below 0" : " is not above 0");
      },
      zero_allowed ? "NONNEGATIVE" : "POSITIVE");
}
inline const CLI::Validator kPositive = number_check(false);
inline const CLI::Validator kNonNegative = number_check(true);

struct StudyGrid {
  std::vector<double> speeds{750, 1100, 1500, 2000, 2500, 3000};  // rpm
  std::vector<double> widths{25, 37, 50};                         // mm
  std::vector<double> fractions{0.3, 0.6, 0.9};                   // of the critical depth
  std::vector<double> runouts{0, 10, 20};                         // um, eccentric
  int seeds = 1;
  bool verbose = false;
  bool quick = false;  // 1100 and 2500 rpm, 37 mm
  // --mill-model FILE: the mill that cuts, with the study's cutter and part
  // (empty: the configuration's model).
  std::string mill_model_file;

  // The grid's options on `app`: --speeds, --widths, --fractions, --runouts
  // (comma-separated lists), --seeds N, --quick, --verbose, --mill-model
  // FILE. The defaults shown are the members' values when this is called;
  // `quick_also` says what else the study's --quick does.
  void add_options(CLI::App& app, const std::string& quick_also) {
    app.add_option("--speeds", speeds, "spindle speeds, rpm")
        ->delimiter(',')
        ->check(kPositive)
        ->capture_default_str();
    app.add_option("--widths", widths, "widths of cut, mm")
        ->delimiter(',')
        ->check(kPositive)
        ->capture_default_str();
    app.add_option("--fractions", fractions,
                   "depths of cut, as fractions of the critical depth at that speed, width and "
                   "feed")
        ->delimiter(',')
        ->check(kPositive)
        ->capture_default_str();
    app.add_option("--runouts", runouts, "eccentric cutter runouts, um")
        ->delimiter(',')
        ->check(kNonNegative)
        ->capture_default_str();
    app.add_option("--seeds", seeds, "noise seeds per cut")
        ->check(kPositive)
        ->capture_default_str();
    app.add_flag("--quick", quick,
                 "1100 and 2500 rpm at 37 mm only" + quick_also +
                     " (unless the flags for those are given too)");
    app.add_flag("--verbose", verbose, "each run, on stderr");
    app.add_option("--mill-model", mill_model_file,
                   "the mill cuts with this MillingModel (text format, e.g. "
                   "cell/models/paper_face_mill_mismatched.textproto) and the study's cutter "
                   "and part; the critical depths keep the configuration's model");
  }

  // After parsing: --quick's speeds and widths, where not given.
  void finish(const CLI::App& app) {
    if (!quick) return;
    if (app.count("--speeds") == 0) speeds = {1100, 2500};
    if (app.count("--widths") == 0) widths = {37};
  }

  // Loads --mill-model's file into `plant` (nothing without one). False,
  // after saying why on stderr, when it cannot.
  bool load_mill_model(smc::config::MillingModel& plant) const {
    if (mill_model_file.empty()) return true;
    try {
      smc::documents::load(mill_model_file, plant);
    } catch (const std::exception& e) {
      std::fprintf(stderr,
                   "--mill-model: %s (a MillingModel in text format, e.g. "
                   "cell/models/paper_face_mill_mismatched.textproto)\n",
                   e.what());
      return false;
    }
    return true;
  }
};

}  // namespace smc::bench
