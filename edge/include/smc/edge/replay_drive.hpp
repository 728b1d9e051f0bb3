#pragma once
// A drive that plays recorded force from a CSV file, for studying the
// modules and supervisors on measured data. It ignores feed commands (the
// recording already happened); a rewrite is acknowledged and recorded.
//
// CSV: a header naming the columns, then one row per sample. Required:
// t_s, f_y_n, f_z_n. Optional: f_x_n, f_y_wide_n (ForceSample; absent: NaN),
// x_mm, depth_mm, spindle_rpm, feedrate_mm_s, pass_index, in_pass (0/1).
// Missing optional columns take the program's values. `smc-edge simulate` writes files in this
// format. The wideband channel replays one sample a period (f_y_wide_n): a configuration that
// expects more (operation.wideband_samples_per_tick above 1) makes module E fail and holds the
// feed at the first finite one; replay such recordings with it at 1.

#include <string>
#include <vector>

#include "smc/edge/drive.hpp"

namespace smc::edge {

class ReplayDrive final : public Drive {
 public:
  // Not real-time: reads the whole file. Throws std::runtime_error naming
  // file:line and the column for a malformed row.
  ReplayDrive(const std::string& path, double sample_period_s);

  void load(const FixedProgram& program) override;
  Status step(double feedrate_cmd_mm_s, DriveSample& out) noexcept override;
  Status rewrite(const FixedProgram& program, int from) noexcept override;
  double sample_period_s() const noexcept override { return period_s_; }

  size_t rows() const noexcept { return rows_.size(); }
  int rewrites() const noexcept { return rewrites_; }

 private:
  struct Row {
    double t_s, f_x_n, f_y_n, f_z_n, f_y_wide_n, x_mm, depth_mm, spindle_rpm, feedrate_mm_s;
    int pass_index;
    bool in_pass;
  };
  std::vector<Row> rows_;
  size_t next_ = 0;
  double period_s_;
  FixedProgram program_;
  int rewrites_ = 0;
};

}  // namespace smc::edge
