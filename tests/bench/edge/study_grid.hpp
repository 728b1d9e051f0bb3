#pragma once
// The grid of cuts the edge studies sweep (chatter detector, tool-breakage
// detector), and the command-line options they share.

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc_config.pb.h"

namespace smc::bench {

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

  // A comma-separated list of numbers.
  static std::vector<double> list(const char* text) {
    std::vector<double> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) out.push_back(std::atof(item.c_str()));
    return out;
  }

  // Takes argv[i] (and its value) when it is one of the grid's options:
  // --speeds, --widths, --fractions, --runouts (lists), --seeds N, --quick,
  // --verbose, --mill-model FILE. Returns false for any other argument.
  bool take(int argc, char** argv, int& i) {
    const bool more = i + 1 < argc;
    const char* a = argv[i];
    if (std::strcmp(a, "--seeds") == 0 && more) {
      seeds = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--speeds") == 0 && more) {
      speeds = list(argv[++i]);
    } else if (std::strcmp(a, "--widths") == 0 && more) {
      widths = list(argv[++i]);
    } else if (std::strcmp(a, "--fractions") == 0 && more) {
      fractions = list(argv[++i]);
    } else if (std::strcmp(a, "--runouts") == 0 && more) {
      runouts = list(argv[++i]);
    } else if (std::strcmp(a, "--mill-model") == 0 && more) {
      mill_model_file = argv[++i];
    } else if (std::strcmp(a, "--verbose") == 0) {
      verbose = true;
    } else if (std::strcmp(a, "--quick") == 0) {
      quick = true;
      speeds = {1100, 2500};
      widths = {37};
    } else {
      return false;
    }
    return true;
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
