#include "smc/supervision/gcode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "smc_config.pb.h"

namespace smc::supervision {

namespace {

// A coordinate or word value: at most 4 decimals, no trailing zeros.
std::string num(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  std::string s(buf);
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

void require(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw std::invalid_argument("G-code: " + field + ": " + what);
}

bool positive(double v) { return std::isfinite(v) && v > 0; }

// RS274NGC comments end at ')' and may not contain '(' : keep titles plain.
std::string comment_text(const std::string& s) {
  std::string out;
  for (char c : s) out += (c == '(' || c == ')' || c == '\n' || c == '\r') ? ' ' : c;
  return out;
}

}  // namespace

std::string render_gcode(const FixedProgram& p, const CutGeometry& g, const GcodeOptions& o) {
  require(p.count > 0 && p.count <= FixedProgram::kMaxPasses, "program.passes",
          "needs 1 to " + std::to_string(FixedProgram::kMaxPasses) + " passes");
  require(o.first_pass >= 0 && o.first_pass < p.count, "first_pass",
          std::to_string(o.first_pass) + " is not a pass of the program");
  require(g.teeth > 0, "cutter.teeth", "must be > 0");
  require(positive(g.cutter_radius_mm), "cutter.radius_mm", "must be > 0");
  require(positive(g.part_length_mm), "workpiece.length_mm", "must be > 0");
  require(std::isfinite(g.approach_mm) && g.approach_mm >= 0, "approach_mm", "must be >= 0");
  require(positive(g.max_feed_per_tooth_mm), "operation.max_feed_per_tooth_mm", "must be > 0");
  require(std::isfinite(g.max_feedrate_mm_s) && g.max_feedrate_mm_s >= 0,
          "machine.max_feedrate_mm_s", "must be >= 0 (0: not known)");
  require(positive(o.safe_z_mm) && positive(o.clearance_mm), "options",
          "safe Z and clearance must be > 0");
  for (int i = o.first_pass; i < p.count; ++i) {
    const auto& s = p.passes[static_cast<size_t>(i)];
    const std::string f = "program.passes[" + std::to_string(i) + "]";
    require(positive(s.depth_mm), f + ".depth_mm", "must be > 0");
    require(positive(s.feedrate_mm_s), f + ".feedrate_mm_s", "must be > 0");
    require(positive(s.spindle_rpm), f + ".spindle_rpm", "must be > 0");
  }

  const double x_start = -(g.cutter_radius_mm + g.approach_mm);
  const double x_end = g.part_length_mm + g.cutter_radius_mm + o.clearance_mm;
  std::string out;
  auto line = [&out](const std::string& l) { out += l + "\n"; };
  if (!o.title.empty()) line("(" + comment_text(o.title) + ")");
  line("(face milling, " + std::to_string(p.count - o.first_pass) + " of " +
       std::to_string(p.count) + " passes, program revision " + std::to_string(p.revision) + ", " +
       num(p.total_depth_mm() - p.depth_before(o.first_pass)) + " mm to remove)");
  line("(frame: X0 part leading edge, part to X" + num(g.part_length_mm) +
       "; Y0 cutter axis; Z0 top face before pass 1)");
  line(
      "(F is the highest feed the supervisor may command; it scales F down with the adaptive "
      "feed)");
  line("G21 G17 G90 G94 G54 G49 G40 G80 G64 P0.01");
  line("M52 P1 (adaptive feed on)");
  line("M53 P1 (feed-hold input on)");
  line("G0 Z" + num(o.safe_z_mm));
  double rpm = 0;
  for (int i = o.first_pass; i < p.count; ++i) {
    const auto& s = p.passes[static_cast<size_t>(i)];
    const double z = -p.depth_before(i + 1);
    double f_max = g.max_feed_per_tooth_mm * g.teeth * s.spindle_rpm;  // mm/min
    if (g.max_feedrate_mm_s > 0) f_max = std::min(f_max, g.max_feedrate_mm_s * 60);
    line("(pass " + std::to_string(i + 1) + " of " + std::to_string(p.count) + ": " +
         num(s.depth_mm) + " mm deep to Z" + num(z) + ", programmed " + num(s.feedrate_mm_s * 60) +
         " mm/min, " + num(s.spindle_rpm) + " rpm)");
    if (s.spindle_rpm != rpm) {
      line("S" + num(s.spindle_rpm) + " M3");
      rpm = s.spindle_rpm;
    }
    line("G0 X" + num(x_start) + " Y0");
    line("G0 Z" + num(z));
    line("G1 X" + num(x_end) + " F" + num(f_max));
    line("G0 Z" + num(o.safe_z_mm));
  }
  line("M5");
  line("M52 P0");
  line("M53 P0");
  line("M2");
  return out;
}

CutGeometry cut_geometry(const smc::config::SupervisorConfig& c) {
  CutGeometry g;
  g.teeth = static_cast<int>(c.operation().teeth());
  g.cutter_radius_mm = c.operation().cutter_radius_mm();
  g.part_length_mm = c.milling_model().workpiece().length_mm();
  // Where the simulated mill starts each pass (sim_mill.cpp), so that both
  // drives cut the same path.
  g.approach_mm = c.simulation().approach_mm() > 0 ? c.simulation().approach_mm()
                  : c.program().approach_mm() > 0  ? c.program().approach_mm()
                                                   : 5.0;
  g.max_feed_per_tooth_mm = c.operation().max_feed_per_tooth_mm();
  g.max_feedrate_mm_s = c.machine().max_feedrate_mm_s();
  return g;
}

std::string render_gcode(const smc::config::SupervisorConfig& c, const GcodeOptions& o) {
  FixedProgram p;
  const auto& passes = c.program().passes();
  if (passes.size() > FixedProgram::kMaxPasses) {
    throw std::invalid_argument("G-code: program.passes: more than " +
                                std::to_string(FixedProgram::kMaxPasses));
  }
  for (const auto& s : passes) {
    p.passes[p.count++] = {s.depth_mm(), s.feedrate_mm_s(), s.spindle_rpm(), s.force_reference_n()};
  }
  p.revision = c.program().revision();
  return render_gcode(p, cut_geometry(c), o);
}

}  // namespace smc::supervision
