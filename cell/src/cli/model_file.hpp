#pragma once
// The --model argument of the physics subcommands (lobes, tds).

#include <string>

#include "registry.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/paper_case.hpp"

namespace smc::cell::cli {

// The milling model in `file`, or the paper's case when no file is given.
// A bad file ends the command with exit code 2 and the file's own errors.
inline machining::MillingModel load_model_or_paper_case(const std::string& file) {
  if (file.empty()) return machining::paper_case();
  try {
    return machining::load_milling_model(file);
  } catch (const std::exception& e) {
    throw Failure(2, std::string(e.what()) +
                         "\n(fix the file, or leave out --model to use the paper's case)");
  }
}

}  // namespace smc::cell::cli
