#pragma once
// The part program as the loop sees it (services/supervision: one program
// model for cell and edge), and the running program the core owns: what
// module F rewrites and the drive executes.

#include "smc/supervision/program.hpp"

namespace smc::edge {

using supervision::add_one_pass;
using supervision::FixedProgram;
using supervision::PassSpec;

// The program in execution: owned by the core, reached by a module through
// Module::attach() (module F rewrites it). Real-time data.
struct RunningProgram {
  FixedProgram program;
  int current_pass = 0;  // the pass the drive is in (or repositioning to)
};

}  // namespace smc::edge
