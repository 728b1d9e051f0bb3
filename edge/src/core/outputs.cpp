// Files written by smc-edge simulate.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "plots.hpp"
#include "smc/documents/load.hpp"
#include "smc/edge/runner.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace {

std::string modules_string(ModuleMask m) {
  const std::string s = supervision::letters(m);
  return s.empty() ? "-" : s;
}

std::string steps_string(const EdgeCore& core, uint64_t steps) {
  std::string s;
  for (int i = 0; i < core.supervisor().step_count(); ++i) {
    if ((steps >> i) & 1) {
      if (!s.empty()) s += ' ';
      s += std::to_string(core.supervisor().step_number(i));
    }
  }
  return s;
}

class CsvFile {
 public:
  explicit CsvFile(const std::filesystem::path& p)
      : path_(p.string()), f_(std::fopen(path_.c_str(), "w")) {
    if (f_ == nullptr) throw std::runtime_error(path_ + ": cannot write");
  }
  ~CsvFile() {
    if (f_ != nullptr) std::fclose(f_);
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  FILE* get() const { return f_; }

 private:
  std::string path_;
  FILE* f_;
};

}  // namespace

void write_outputs(const std::string& dir, const EdgeCore& core, const RunResult& run,
                   const smc::config::RunSummary& summary) {
  const std::filesystem::path out(dir);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the output folder: " + ec.message());

  {
    CsvFile f(out / "samples.csv");
    std::fprintf(f.get(),
                 "t_s,x_mm,pass_index,in_pass,depth_mm,f_y_n,f_z_n,f_y_wide_n,f_y_peak_n,f_ref_n,"
                 "feedrate_mm_s,spindle_rpm,power_w,vibration_y_mm,contact,modules,steps\n");
    for (const auto& s : run.samples) {
      std::fprintf(f.get(),
                   "%.4f,%.3f,%d,%d,%.3f,%.2f,%.2f,%.2f,%.2f,%.2f,%.3f,%.1f,%.1f,%.6f,%d,%s,%s\n",
                   s.t_s, s.x_mm, s.pass_index, s.in_pass ? 1 : 0, s.depth_mm, s.f_y_n, s.f_z_n,
                   s.f_y_wide_n, s.f_y_peak_n, s.f_ref_n, s.feedrate_mm_s, s.spindle_rpm, s.power_w,
                   s.vibration_y_mm, s.contact ? 1 : 0, modules_string(s.active).c_str(),
                   steps_string(core, s.steps).c_str());
    }
  }
  {
    CsvFile f(out / "revolutions.csv");
    std::fprintf(f.get(),
                 "t_s,revolution,pass_index,pass_count,x_mm,depth_mm,f_y_peak_n,f_ref_n,"
                 "feedrate_mm_s,feed_per_tooth_mm,power_peak_w,power_mean_w,chatter_ratio,"
                 "chatter_vibration_ratio,chatter_vibration_flip,gain_estimate,"
                 "engagement,contact,chatter,fault_hold,modules,steps\n");
    for (const auto& r : run.revolutions) {
      std::fprintf(f.get(),
                   "%.4f,%u,%d,%d,%.3f,%.3f,%.2f,%.2f,%.3f,%.5f,%.1f,%.1f,%.4f,%.4f,%.4f,%.2f,%.3f,"
                   "%d,%d,%d,%s,%s\n",
                   r.t_s, r.revolution, r.pass_index, r.pass_count, r.x_mm, r.depth_mm,
                   r.f_y_peak_n, r.f_ref_n, r.feedrate_mm_s, r.feed_per_tooth_mm, r.power_peak_w,
                   r.power_mean_w, r.chatter_ratio, r.chatter_vibration_ratio,
                   r.chatter_vibration_flip, r.gain_estimate, r.engagement_min, r.contact ? 1 : 0,
                   r.chatter ? 1 : 0, r.fault_hold ? 1 : 0, modules_string(r.active).c_str(),
                   steps_string(core, r.active_steps).c_str());
    }
  }
  {
    CsvFile f(out / "events.csv");
    std::fprintf(f.get(), "t_s,event,pass_index,pass_count,depth_mm,steps,modules,detail\n");
    for (const auto& e : run.events) {
      std::string detail;
      if (e.kind == EventKind::kFault) {
        detail = to_string(e.fault);
        if (e.module >= 0)
          detail += " in module " + std::string(1, letter(static_cast<ModuleId>(e.module)));
        if (e.why != nullptr) {
          std::string why = e.why;
          std::replace(why.begin(), why.end(), ',', ';');  // one CSV field
          detail += " (" + why + ")";
        }
      } else if (e.kind == EventKind::kChatterDetected) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "ratio %.3f at %.0f Hz", e.ratio, e.frequency_hz);
        detail = buf;
      }
      std::fprintf(f.get(), "%.4f,%s,%d,%d,%.3f,%s,%s,%s\n", e.t_s, to_string(e.kind), e.pass_index,
                   e.pass_count, e.depth_mm, steps_string(core, e.active_steps).c_str(),
                   modules_string(e.active).c_str(), detail.c_str());
    }
  }
  {
    std::ofstream j(out / "summary.json");
    j << smc::documents::to_json(summary) << "\n";
    if (!j) throw std::runtime_error((out / "summary.json").string() + ": cannot write");
  }
  write_plots(out.string(), core, run, summary);
}

}  // namespace smc::edge
