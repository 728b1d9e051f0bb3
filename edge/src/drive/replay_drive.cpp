#include "smc/edge/replay_drive.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace smc::edge {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  return out;
}

}  // namespace

ReplayDrive::ReplayDrive(const std::string& path, double sample_period_s)
    : period_s_(sample_period_s) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the replay file");
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + ":1: empty file; need a header");
  std::map<std::string, size_t> col;
  const auto header = split(line);
  for (size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  for (const char* need : {"t_s", "f_y_n", "f_z_n"}) {
    if (!col.count(need)) {
      throw std::runtime_error(path + ":1: header has no column '" + need +
                               "' (need t_s, f_y_n, f_z_n)");
    }
  }
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    const auto cells = split(line);
    auto get = [&](const char* name, double fallback) {
      auto it = col.find(name);
      if (it == col.end()) return fallback;
      if (it->second >= cells.size()) {
        throw std::runtime_error(path + ":" + std::to_string(lineno) + ": missing column '" + name +
                                 "'");
      }
      const std::string& c = cells[it->second];
      char* end = nullptr;
      const double v = std::strtod(c.c_str(), &end);
      // "nan" and "inf" parse: a recording may hold bad samples, and the
      // edge must meet them as a real sensor's would be met.
      if (end == c.c_str() || *end != '\0') {
        throw std::runtime_error(path + ":" + std::to_string(lineno) + ": column '" + name +
                                 "' is not a number: '" + c + "'");
      }
      return v;
    };
    Row r{};
    r.t_s = get("t_s", 0);
    r.f_x_n = get("f_x_n", 0);
    r.f_y_n = get("f_y_n", 0);
    r.f_z_n = get("f_z_n", 0);
    r.f_y_wide_n = get("f_y_wide_n", std::nan(""));
    r.x_mm = get("x_mm", 0);
    r.depth_mm = get("depth_mm", -1);
    r.spindle_rpm = get("spindle_rpm", -1);
    r.feedrate_mm_s = get("feedrate_mm_s", -1);
    r.pass_index = static_cast<int>(get("pass_index", 0));
    r.in_pass = get("in_pass", 1) != 0;
    rows_.push_back(r);
  }
  if (rows_.empty()) throw std::runtime_error(path + ": no samples after the header");
}

void ReplayDrive::load(const FixedProgram& program) {
  program_ = program;
  next_ = 0;
  rewrites_ = 0;
}

Status ReplayDrive::step(double /*feedrate_cmd_mm_s*/, DriveSample& out) noexcept {
  if (next_ >= rows_.size()) {
    out.in_pass = false;
    out.program_done = true;
    return Status::kOk;
  }
  const Row& r = rows_[next_++];
  const int pass = r.pass_index < program_.count ? r.pass_index : 0;
  const PassSpec& spec = program_.passes[static_cast<size_t>(pass)];
  out.force = ForceSample{r.t_s, r.f_x_n, r.f_y_n, r.f_z_n, r.f_y_wide_n};
  out.spindle_rpm = r.spindle_rpm >= 0 ? r.spindle_rpm : spec.spindle_rpm;
  out.depth_mm = r.depth_mm >= 0 ? r.depth_mm : spec.depth_mm;
  out.programmed_feedrate_mm_s = spec.feedrate_mm_s;
  out.feedrate_mm_s = r.feedrate_mm_s >= 0 ? r.feedrate_mm_s : spec.feedrate_mm_s;
  out.x_mm = r.x_mm;
  out.spindle_power_w = std::nan("");  // a force recording has no spindle power
  out.pass_index = pass;
  out.in_pass = r.in_pass;
  out.program_done = next_ >= rows_.size();
  return Status::kOk;
}

Status ReplayDrive::rewrite(const FixedProgram& program, int /*from*/) noexcept {
  program_ = program;
  ++rewrites_;
  return Status::kOk;
}

}  // namespace smc::edge
