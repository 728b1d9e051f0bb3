#pragma once
// The part program as an RS274NGC (G-code) program for a CNC control, as
// LinuxCNC 2.9 reads it: face-milling passes along +X with approach, Z
// levels, retract, spindle S and feed F in mm/min, the adaptive feed (M52 P1)
// and the feed-hold input (M53 P1) enabled. A rendering of FixedProgram —
// the one program model that the cell plans, module F rewrites and every
// drive runs — never a second model. Not real-time (it builds a string).
//
// Frame (the simulated mill's, services/machining): X along the feed, X0 at
// the part's leading edge, the part ends at X = part_length_mm; Y0 is the
// cutter axis (the part's width band lies at the workpiece offset from it);
// Z0 is the part's top face before pass 0. Each pass starts in air at
// X = -(radius + approach), goes down to its Z level there, cuts to
// X = length + radius + clearance (the cutter clear of the part) and
// retracts to the safe Z.
//
// F: LinuxCNC's motion.adaptive-feed is clamped to [0, 1], so the edge can
// only slow the programmed feed: F is the highest feed the edge may command
// for the pass (max feed per tooth x teeth x rev/min, capped by the
// machine's max feedrate when known). LinuxCNC caps F at the axes' maximum
// velocity and then scales it by the adaptive feed, so a drive turns a feed
// command into the scale against min(F, axis max velocity). The programmed
// feedrate the supervisor starts from is in each pass's comment.

#include <string>

#include "smc/supervision/program.hpp"

namespace smc::config {
class SupervisorConfig;
}

namespace smc::supervision {

struct CutGeometry {
  int teeth = 0;
  double cutter_radius_mm = 0;
  double part_length_mm = 0;
  double approach_mm = 5;            // air before the cutter edge meets the part
  double max_feed_per_tooth_mm = 0;  // the edge's upper clamp: sets F
  double max_feedrate_mm_s = 0;      // the machine's; caps F (0: not known)
};

struct GcodeOptions {
  std::string title;        // first comment line (job, part, configuration)
  int first_pass = 0;       // render passes [first_pass, count): a rewrite's remainder
  double safe_z_mm = 10;    // above the part's top face
  double clearance_mm = 2;  // past the part's far edge before retracting
};

// Throws std::invalid_argument naming the field when the program or the
// geometry cannot make a program (no passes, a non-positive depth, feed,
// speed, radius or length, a NaN, first_pass out of range).
std::string render_gcode(const FixedProgram& program, const CutGeometry& geometry,
                         const GcodeOptions& options = {});

// The configuration's cutter, part length, approach and feed clamp.
CutGeometry cut_geometry(const smc::config::SupervisorConfig& config);

// The configuration's program, cutter, part length and feed clamp.
std::string render_gcode(const smc::config::SupervisorConfig& config,
                         const GcodeOptions& options = {});

}  // namespace smc::supervision
