#include "smc/edge/linuxcnc_drive.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <numbers>
#include <thread>
#include <vector>

#include "cnc_control.hpp"
#include "hal_stream.hpp"
#include "smc/supervision/gcode.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace {

// The axis stands still: what a rewrite's hand-over, a broken tool's lift
// and an MDI move's end each wait for.
bool at_standstill(const linuxcnc::CncStatus& st) noexcept {
  return std::fabs(st.velocity_mm_s) <= 1e-3;
}

std::int64_t now_ns() noexcept {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

// Which pass each cutting line (G1) of a rendered program belongs to.
struct LineMap {
  std::array<int, FixedProgram::kMaxPasses> g1_line{};  // 1-based file line
  int first_pass = 0;
  int count = 0;
};

LineMap map_lines(const std::string& gcode, int first_pass) {
  LineMap m;
  m.first_pass = first_pass;
  int line = 1;
  std::size_t pos = 0;
  while (pos < gcode.size()) {
    if (gcode.compare(pos, 3, "G1 ") == 0 && m.count < FixedProgram::kMaxPasses) {
      m.g1_line[static_cast<std::size_t>(m.count++)] = line;
    }
    pos = gcode.find('\n', pos);
    if (pos == std::string::npos) break;
    ++pos;
    ++line;
  }
  return m;
}

enum class CncFault : int { kNone, kStale, kEstop, kOff, kNotAuto, kProgram, kLinuxCnc };

}  // namespace

struct LinuxCncDrive::Impl {
  smc::config::SupervisorConfig config;
  LinuxCncDriveOptions opt;
  double period_s = 0;
  std::unique_ptr<linuxcnc::CncControl> cnc;
  std::unique_ptr<linuxcnc::HalSampleStream> stream;
  double axis_max_mm_s = 0;

  // The program as the loop knows it, and the line map of what LinuxCNC runs.
  FixedProgram program;
  std::array<LineMap, 2> maps{};
  std::atomic<int> map_index{0};
  // Engagement: tooth-tip angles on the leading half over the part's band.
  std::vector<double> band_cos;
  double radius_mm = 0, length_mm = 0;

  // Loop → control thread.
  std::atomic<bool> loop_live{false};
  std::atomic<int> rewrite_asked{0};  // generation
  FixedProgram rewrite_program;       // written by the loop before rewrite_asked
  int rewrite_from = 0;
  // O's speed change: the override on the programmed speed, and its
  // generation.
  std::atomic<double> speed_scale{1.0};
  std::atomic<int> speed_asked{0};
  // N's breakage: lift the tool clear (retract()).
  std::atomic<bool> retract_asked{false};
  // Control thread → loop.
  std::atomic<bool> retract_moving{false};  // a lift runs: the feed is released for it
  std::atomic<int> rewrite_done{0};
  std::atomic<bool> done{false};
  std::atomic<int> fault{static_cast<int>(CncFault::kNone)};
  mutable std::mutex why_mu;
  std::string why;  // the fault's words (control thread, or stale from the loop)
  std::string last_path;
  std::thread control;
  std::atomic<bool> stop{false};

  // Loop state.
  linuxcnc::HalRecord rec{};
  std::int64_t last_record_ns = 0;
  std::uint64_t ticks = 0;
  int pass = 0;
  bool in_pass = false;
  bool job_start_high = false;
  std::uint64_t drained = 0;  // records from before the job

  void set_fault(CncFault f, const std::string& words) {
    int none = static_cast<int>(CncFault::kNone);
    if (fault.compare_exchange_strong(none, static_cast<int>(f))) {
      std::lock_guard lk(why_mu);
      why = words;
    }
  }

  supervision::CutGeometry geometry;

  // Not real-time: renders passes [first_pass, count) of `p`, writes them
  // to the program folder, and maps their cutting lines.
  std::string write_program(const FixedProgram& p, int first_pass, LineMap& map) {
    supervision::GcodeOptions go;
    go.title =
        "smc-edge " + opt.machine_id + ", configuration " + config.config_id() +
        (first_pass > 0 ? ", the rewrite's remainder from pass " + std::to_string(first_pass + 1)
                        : "");
    go.first_pass = first_pass;
    const std::string text = supervision::render_gcode(p, geometry, go);
    // Made readable to LinuxCNC's user when the edge makes it.
    if (std::filesystem::create_directories(opt.program_dir)) {
      std::filesystem::permissions(
          opt.program_dir,
          std::filesystem::perms::owner_all | std::filesystem::perms::group_read |
              std::filesystem::perms::group_exec | std::filesystem::perms::others_read |
              std::filesystem::perms::others_exec,
          std::filesystem::perm_options::add);
    }
    // <machine>-<configuration>-r<revision>-p<first pass>.ngc: one name per
    // program LinuxCNC ran (a configuration is one job's attempt).
    std::string cfg_id = config.config_id();
    for (char& ch : cfg_id) {
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_') ch = '_';
    }
    const std::string path = opt.program_dir + "/" + opt.machine_id + "-" + cfg_id + "-r" +
                             std::to_string(p.revision) + "-p" + std::to_string(first_pass + 1) +
                             ".ngc";
    {
      std::ofstream out(path, std::ios::trunc);
      out << text;
      if (!out) throw std::runtime_error(path + ": cannot write the program");
    }
    map = map_lines(text, first_pass);
    last_path = path;
    return path;
  }

  // Module E's wideband channel, before anything moves: the dynamometer
  // must bring the samples a period E was told
  // (operation.wideband_samples_per_tick), or E fails at the first sample
  // in contact and the feed is held mid-cut. Read on a fresh servo record
  // (up to 200 ms); none, or no wideband channel on the sensor, leaves it
  // to the loop (the stale-record fault; E judging without the channel).
  void check_wideband_channel() {
    using namespace std::chrono_literals;
    const unsigned takes = supervision::wideband_samples_e_takes(config);
    if (takes == 0) return;
    linuxcnc::HalRecord r;
    bool got = false;
    for (int i = 0; i < 200 && !(got = stream->read(r)); ++i) std::this_thread::sleep_for(1ms);
    if (!got || !r.fy_wide_present) return;
    ++drained;  // before the job's first tick: not the job's
    const unsigned brings = static_cast<unsigned>(std::max<std::int32_t>(1, r.fy_wide_samples));
    if (brings == takes) return;
    throw std::runtime_error(
        "LinuxCNC's dynamometer gives module E's wideband channel " + std::to_string(brings) +
        " samples a period (smc-force-y-wide-samples), but the configuration says " +
        std::to_string(takes) +
        " (operation.wideband_samples_per_tick), and E would hold the feed at the first "
        "sample in contact; nothing was moved. Fix: give the machine's catalog record its "
        "sensor's channel (wideband { samples_per_tick: " +
        std::to_string(brings) + " ... }), or start the dynamometer at " + std::to_string(takes) +
        " (simulation.f_y_wide_samples_per_tick of run.sh start --dyno CONFIG)");
  }

  void control_loop();
  // The control thread's part of retract(): standstill, abort, a rapid to
  // the safe Z in MDI, and wait until the move stopped there.
  void lift();
  // Runs one MDI line that moves the tool (LinuxCNC's program aborted
  // before), with the feed released for it, and returns once the
  // interpreter is idle and the axes stand still; throws on LinuxCNC's
  // error or after 10 s (60 mm at the slowest rapid configured).
  void mdi_move(const std::string& line);
};

LinuxCncDrive::LinuxCncDrive(const smc::config::SupervisorConfig& config, double sample_period_s,
                             LinuxCncDriveOptions options)
    : impl_(std::make_unique<Impl>()), period_s_(sample_period_s) {
  Impl& d = *impl_;
  d.config = config;
  d.opt = std::move(options);
  d.period_s = sample_period_s;
  d.geometry = supervision::cut_geometry(config);
  d.radius_mm = d.geometry.cutter_radius_mm;
  d.length_mm = d.geometry.part_length_mm;
  const auto& w = config.milling_model().workpiece();
  const double y_lo = w.offset_mm() - w.width_mm() / 2, y_hi = w.offset_mm() + w.width_mm() / 2;
  for (int k = 0; k < 181; ++k) {
    const double th = -std::numbers::pi / 2 + std::numbers::pi * k / 180.0;
    const double y = d.radius_mm * std::sin(th);
    if (y >= y_lo && y <= y_hi) d.band_cos.push_back(std::cos(th));
  }
  d.cnc = std::make_unique<linuxcnc::CncControl>(d.opt.nml_file);
}

LinuxCncDrive::~LinuxCncDrive() {
  Impl& d = *impl_;
  d.stop = true;
  if (d.control.joinable()) d.control.join();
  if (d.stream) {
    d.stream->set_adaptive_feed(0);
    d.stream->set_feed_inhibit(true);
  }
  // A program still running (the job was stopped or failed) is aborted: the
  // machine never runs on without its supervisor.
  if (!d.done) {
    try {
      d.cnc->abort();
    } catch (const std::exception& e) {
      spdlog::error("{}: cannot abort LinuxCNC's program: {}", d.opt.machine_id, e.what());
    }
  }
}

void LinuxCncDrive::load(const FixedProgram& program) {
  Impl& d = *impl_;
  if (d.control.joinable()) throw std::logic_error("LinuxCncDrive::load: one job per drive");
  d.cnc->require_ready();
  d.axis_max_mm_s = d.cnc->status().max_velocity_mm_s;
  d.program = program;
  const std::string path = d.write_program(program, 0, d.maps[0]);
  d.map_index = 0;
  d.cnc->open_program(path);
  // Join HAL with the feed held until the loop runs.
  d.stream = std::make_unique<linuxcnc::HalSampleStream>(d.opt.machine_id, 0, true);
  if (!d.stream->outputs_linked()) {
    throw std::runtime_error(
        "LinuxCNC's HAL has no smc-adaptive-feed/smc-feed-inhibit signals: load "
        "deploy/linuxcnc/smc-edge.hal (the shipped smc-mill.ini does)");
  }
  d.stream->set_adaptive_feed(0);
  d.stream->set_feed_inhibit(true);
  d.stream->set_job_start(true);
  d.job_start_high = true;
  // Records from before this job are not this job's.
  linuxcnc::HalRecord skip;
  while (d.stream->read(skip)) ++d.drained;
  d.check_wideband_channel();
  d.last_record_ns = now_ns();
  spdlog::info("{}: LinuxCNC opened {} ({} passes); axes at most {:.1f} mm/s", d.opt.machine_id,
               path, program.count, d.axis_max_mm_s);
  d.control = std::thread([&d] { d.control_loop(); });
}

void LinuxCncDrive::Impl::control_loop() {
  using namespace std::chrono_literals;
  // Start once the loop beats, so that the machine never moves unsupervised.
  while (!stop && !loop_live) std::this_thread::sleep_for(1ms);
  if (stop) return;
  try {
    // A speed change of an earlier job stays in LinuxCNC until changed.
    cnc->set_spindle_override(1.0);
    cnc->run();
    spdlog::info("{}: LinuxCNC runs {}", opt.machine_id, last_path);
  } catch (const std::exception& e) {
    set_fault(CncFault::kProgram, e.what());
    return;
  }
  int handled = 0;
  int speed_handled = 0;
  int idle_polls = 0;
  // The axis must stand still before a rewrite is handed over or a broken
  // tool is lifted. The loop holds the feed; an axis still moving 10 s
  // later is a fault with its velocity, not a job that waits for ever.
  std::chrono::steady_clock::time_point moving_since{};
  auto standing = [&](const linuxcnc::CncStatus& st, const char* what) {
    if (at_standstill(st)) {
      moving_since = {};
      return true;
    }
    const auto now = std::chrono::steady_clock::now();
    if (moving_since == std::chrono::steady_clock::time_point{}) moving_since = now;
    if (now - moving_since > 10s) {
      char words[200];
      std::snprintf(words, sizeof words,
                    "the axis still moved at %.3f mm/s 10 s after the feed was held for %s",
                    st.velocity_mm_s, what);
      set_fault(CncFault::kLinuxCnc, words);
    }
    return false;
  };
  // A lift asked for is finished even when the drive is being destroyed
  // (the run ends a second after a breakage): the tool is not left in the
  // part half-way up. Each LinuxCNC command is bounded by its timeout.
  std::chrono::steady_clock::time_point stopping{};
  while (!stop || retract_asked.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(5ms);
    if (stop) {  // only a lift keeps the thread, and not for ever
      const auto now = std::chrono::steady_clock::now();
      if (stopping == std::chrono::steady_clock::time_point{}) stopping = now;
      if (now - stopping > 10s) {
        set_fault(CncFault::kProgram, "the broken tool's lift did not start within 10 s");
        return;
      }
    }
    linuxcnc::CncStatus st;
    try {
      st = cnc->status();
      for (const auto& m : cnc->take_errors()) {
        spdlog::warn("{}: LinuxCNC: {}", opt.machine_id, m);
        set_fault(CncFault::kLinuxCnc, "LinuxCNC: " + m);
      }
    } catch (const std::exception& e) {
      set_fault(CncFault::kLinuxCnc, e.what());
      return;
    }
    if (st.estop)
      set_fault(CncFault::kEstop, "LinuxCNC went into E-stop during the job");
    else if (!st.on)
      set_fault(CncFault::kOff, "LinuxCNC's machine was switched off during the job");
    else if (!st.auto_mode && !retract_asked.load(std::memory_order_acquire)) {
      set_fault(CncFault::kNotAuto,
                "LinuxCNC left auto mode during the job (an operator or "
                "another program took it to manual or MDI)");
    }
    if (fault != static_cast<int>(CncFault::kNone)) {
      try {
        cnc->abort();
      } catch (const std::exception&) {
      }
      return;
    }
    if (retract_asked.load(std::memory_order_acquire)) {
      // A safe point: the feed is held by the loop; wait for standstill.
      if (!standing(st, "the broken tool's lift")) continue;
      lift();  // the thread's last act
      return;
    }
    const int speed = speed_asked.load(std::memory_order_acquire);
    if (speed != speed_handled) {
      const double scale = speed_scale.load(std::memory_order_relaxed);
      try {
        cnc->set_spindle_override(scale);
        spdlog::info("{}: LinuxCNC's spindle override set to {:.3f} (module O)", opt.machine_id,
                     scale);
      } catch (const std::exception& e) {
        set_fault(CncFault::kLinuxCnc, std::string("setting the spindle override: ") + e.what());
        return;
      }
      speed_handled = speed;
    }
    const int asked = rewrite_asked.load(std::memory_order_acquire);
    if (asked != handled) {
      // A safe point: the feed is held by the loop; wait for standstill.
      if (!standing(st, "the rewritten program's hand-over")) continue;
      try {
        // The tool stands in the cut. LinuxCNC's abort also stops the
        // spindle; the remainder's first move lifts the tool only once it
        // runs, and opening it can take most of a second, during which the
        // spindle ran down in the cut (a LinuxCNC run: the chatter regrew
        // to the force sensor's limit). So the spindle is started again at
        // the remainder's speed and the tool lifted to the safe Z in one
        // MDI line (M3 runs before the move) before the remainder is
        // handed over. The override goes back to 1 first: the remainder's
        // G-code carries the speed O chose.
        cnc->abort();
        cnc->set_spindle_override(1.0);
        speed_handled = speed_asked.load(std::memory_order_acquire);
        const int first = std::clamp(rewrite_from, 0, std::max(0, rewrite_program.count - 1));
        const double rpm = rewrite_program.passes[static_cast<std::size_t>(first)].spindle_rpm;
        const double safe_z = supervision::GcodeOptions{}.safe_z_mm;
        char clear[128];
        if (rpm > 0 && std::isfinite(rpm)) {
          std::snprintf(clear, sizeof clear, "G21 G90 G54 M3 S%.0f G0 Z%.3f", rpm, safe_z);
        } else {
          std::snprintf(clear, sizeof clear, "G21 G90 G54 G0 Z%.3f", safe_z);
        }
        mdi_move(clear);
        LineMap& m = maps[static_cast<std::size_t>(1 - map_index.load())];
        const std::string path = write_program(rewrite_program, rewrite_from, m);
        cnc->open_program(path);
        map_index.store(1 - map_index.load(), std::memory_order_release);
        cnc->run();
        spdlog::info("{}: LinuxCNC runs the rewritten program {} from pass {}", opt.machine_id,
                     path, rewrite_from + 1);
      } catch (const std::exception& e) {
        set_fault(CncFault::kProgram,
                  std::string("handing the rewritten program over: ") + e.what());
        return;
      }
      handled = asked;
      rewrite_done.store(asked, std::memory_order_release);
      idle_polls = 0;
      continue;
    }
    // The program ended (M2) when the interpreter stays idle.
    idle_polls = st.interp_idle ? idle_polls + 1 : 0;
    if (idle_polls >= 3) {
      done = true;
      return;
    }
  }
}

void LinuxCncDrive::Impl::mdi_move(const std::string& line) {
  using namespace std::chrono_literals;
  retract_moving.store(true, std::memory_order_release);
  try {
    cnc->mdi(line);
    const auto until = std::chrono::steady_clock::now() + 10s;
    int still = 0;
    while (std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(5ms);
      const linuxcnc::CncStatus now = cnc->status();
      for (const auto& m : cnc->take_errors()) {
        throw std::runtime_error("LinuxCNC: " + m);
      }
      still = now.interp_idle && at_standstill(now) ? still + 1 : 0;
      if (still >= 3) {
        retract_moving.store(false, std::memory_order_release);
        return;
      }
    }
    throw std::runtime_error("'" + line + "' did not end within 10 s");
  } catch (...) {
    retract_moving.store(false, std::memory_order_release);
    throw;
  }
}

void LinuxCncDrive::Impl::lift() {
  const double safe_z = supervision::GcodeOptions{}.safe_z_mm;  // the programs' own
  try {
    cnc->abort();
    char line[96];
    std::snprintf(line, sizeof line, "G21 G90 G54 G0 Z%.3f", safe_z);
    mdi_move(line);
    spdlog::warn("{}: tool broken: LinuxCNC lifted it to Z{:.1f}", opt.machine_id, safe_z);
  } catch (const std::exception& e) {
    set_fault(CncFault::kProgram,
              std::string("lifting the broken tool: ") + e.what() + "; clear the tool by hand");
  }
}

bool LinuxCncDrive::wait_sample() noexcept {
  Impl& d = *impl_;
  if (!d.stream) return false;
  const std::int64_t until =
      d.last_record_ns + static_cast<std::int64_t>(d.opt.stale_after_s * 1e9) + 1'000'000;
  while (d.stream->backlog() <= 0) {
    if (now_ns() >= until) return false;
    timespec pause{0, 50'000};
    nanosleep(&pause, nullptr);
  }
  return true;
}

Status LinuxCncDrive::step(double feedrate_cmd_mm_s, DriveSample& out) noexcept {
  Impl& d = *impl_;
  if (!d.stream) return Status::kError;
  const std::int64_t now = now_ns();
  d.stream->heartbeat(now);
  d.loop_live.store(true, std::memory_order_release);
  ++d.ticks;
  if (d.job_start_high && d.ticks > 20) {  // 10 ms: the servo thread has seen it
    d.stream->set_job_start(false);
    d.job_start_high = false;
  }
  if (d.stream->read(d.rec)) {
    d.last_record_ns = now;
  } else if (static_cast<double>(now - d.last_record_ns) > d.opt.stale_after_s * 1e9) {
    d.fault.store(static_cast<int>(CncFault::kStale));  // words in fault()
  }
  const bool faulted = d.fault.load(std::memory_order_acquire) != static_cast<int>(CncFault::kNone);
  // A lift (after a breakage) is also not a pass: LinuxCNC's program is
  // aborted and the move is MDI.
  const bool retracting = d.retract_asked.load(std::memory_order_relaxed);
  const bool rewriting = retracting || d.rewrite_asked.load(std::memory_order_relaxed) !=
                                           d.rewrite_done.load(std::memory_order_acquire);
  // Where LinuxCNC is in the program: the cutting line (G1) of a pass is the
  // pass; the moves between (rapid positioning in air) are not.
  const LineMap& map =
      d.maps[static_cast<std::size_t>(d.map_index.load(std::memory_order_acquire))];
  if (!rewriting) {
    d.pass = map.first_pass;
    d.in_pass = false;
    for (int k = map.count - 1; k >= 0; --k) {
      const int line = map.g1_line[static_cast<std::size_t>(k)];
      if (d.rec.program_line >= line) {
        d.pass = map.first_pass + k;
        d.in_pass = d.rec.program_line == line;
        break;
      }
    }
  } else {
    d.in_pass = false;
  }
  // The feed. In a pass: the share of what LinuxCNC runs the G1 at, held on
  // a command of 0 (the supervisor's hold). Between passes LinuxCNC runs
  // the program's own positioning, as the simulated mill does. Held for good
  // after a fault, and while a rewrite is handed over.
  const int pass_now = std::clamp(d.pass, 0, std::max(0, d.program.count - 1));
  const PassSpec& spec = d.program.passes[static_cast<std::size_t>(pass_now)];
  double f_max = d.geometry.max_feed_per_tooth_mm * d.geometry.teeth * spec.spindle_rpm / 60.0;
  if (d.geometry.max_feedrate_mm_s > 0) f_max = std::min(f_max, d.geometry.max_feedrate_mm_s);
  if (d.axis_max_mm_s > 0) f_max = std::min(f_max, d.axis_max_mm_s);
  // The lift's move alone runs with the feed released.
  const bool lifting = d.retract_moving.load(std::memory_order_acquire);
  const bool hold = !lifting && (faulted || rewriting || (d.in_pass && !(feedrate_cmd_mm_s > 0)));
  d.stream->set_feed_inhibit(hold);
  double share = d.in_pass && f_max > 0 ? feedrate_cmd_mm_s / f_max : 1.0;
  if (hold) share = 0;
  d.stream->set_adaptive_feed(share);

  const PassSpec& cur = d.program.passes[static_cast<std::size_t>(
      std::clamp(d.pass, 0, std::max(0, d.program.count - 1)))];
  // The wideband F_y where the sensor has the channel; NaN (none) where it
  // leaves the signals undriven, which read 0, not a force.
  out.force = ForceSample{
      static_cast<double>(d.ticks) * d.period_s, d.rec.fx_n, d.rec.fy_n, d.rec.fz_n,
      d.rec.fy_wide_present ? d.rec.fy_wide_n : std::numeric_limits<double>::quiet_NaN()};
  // Where the channel samples faster than the servo period, its earlier
  // samples of the period too (smc-force-y-wide-samples; 0 or 1: one).
  if (d.rec.fy_wide_present && d.rec.fy_wide_samples > 1) {
    const int n = std::min<int>(d.rec.fy_wide_samples, 5);
    out.force.wide_count = n;
    for (int i = 0; i < n - 1; ++i) out.force.f_y_wide_sub_n[i] = d.rec.fy_wide_sub_n[i];
    out.force.f_y_wide_sub_n[n - 1] = d.rec.fy_wide_n;
  }
  // The tool's vibration where the machine has it (the virtual
  // dynamometer's, for the chatter label); NaN where it has none.
  out.vibration_y_mm =
      d.rec.vibration_present ? d.rec.vibration_y_mm : std::numeric_limits<double>::quiet_NaN();
  out.spindle_rpm = d.rec.spindle_rps * 60.0;
  out.depth_mm = cur.depth_mm;
  out.programmed_feedrate_mm_s = cur.feedrate_mm_s;
  out.feedrate_mm_s = d.in_pass ? d.rec.velocity_mm_s : 0.0;
  out.x_mm = d.rec.x_mm;
  out.pass_index = d.pass;
  out.in_pass = d.in_pass;
  out.program_done = d.done.load(std::memory_order_acquire) && !rewriting;
  int in_cut = 0;
  if (d.in_pass) {
    for (double c : d.band_cos) {
      const double tip = d.rec.x_mm + d.radius_mm * c;
      if (tip >= 0 && tip <= d.length_mm) ++in_cut;
    }
  }
  out.engagement = d.band_cos.empty()
                       ? 0.0
                       : static_cast<double>(in_cut) / static_cast<double>(d.band_cos.size());
  return faulted ? Status::kError : Status::kOk;
}

Status LinuxCncDrive::rewrite(const FixedProgram& program, int from) noexcept {
  Impl& d = *impl_;
  if (from < 0 || from >= program.count || !d.stream) return Status::kError;
  // One hand-over at a time: the control thread reads the program being
  // handed over (a rewrite before the last one was cut is an error).
  if (d.rewrite_asked.load(std::memory_order_relaxed) !=
      d.rewrite_done.load(std::memory_order_acquire)) {
    return Status::kError;
  }
  d.stream->set_feed_inhibit(true);
  d.stream->set_adaptive_feed(0);
  d.program = program;
  d.rewrite_program = program;
  d.rewrite_from = from;
  d.pass = from;
  d.in_pass = false;
  d.rewrite_asked.fetch_add(1, std::memory_order_release);
  return Status::kOk;
}

Status LinuxCncDrive::retract() noexcept {
  Impl& d = *impl_;
  if (!d.stream) return Status::kError;
  d.stream->set_feed_inhibit(true);
  d.stream->set_adaptive_feed(0);
  d.in_pass = false;
  d.retract_asked.store(true, std::memory_order_release);
  return Status::kOk;
}

Status LinuxCncDrive::change_spindle_speed(double rpm) noexcept {
  Impl& d = *impl_;
  if (!(rpm > 0) || !std::isfinite(rpm) || !d.stream || d.program.count <= 0) {
    return Status::kError;
  }
  // LinuxCNC runs the program the drive last handed it: the override is
  // on that program's speed for the pass in progress (a plan's passes share
  // one speed; a rewrite's remainder carries the new one).
  const int pass = std::clamp(d.pass, 0, d.program.count - 1);
  const double programmed = d.program.passes[static_cast<std::size_t>(pass)].spindle_rpm;
  if (!(programmed > 0)) return Status::kError;
  d.speed_scale.store(rpm / programmed, std::memory_order_relaxed);
  d.speed_asked.fetch_add(1, std::memory_order_release);
  return Status::kOk;
}

std::string LinuxCncDrive::fault() const {
  const Impl& d = *impl_;
  const int f = d.fault.load();
  if (f == static_cast<int>(CncFault::kNone)) return {};
  if (f == static_cast<int>(CncFault::kStale)) {
    return "LinuxCNC's servo records stopped coming (none for " +
           std::to_string(static_cast<int>(d.opt.stale_after_s * 1000)) +
           " ms): its servo thread stalled or LinuxCNC stopped";
  }
  std::lock_guard lk(d.why_mu);
  return d.why;
}

std::uint64_t LinuxCncDrive::lost_samples() const noexcept {
  return impl_->stream ? impl_->stream->lost() : 0;
}
std::uint64_t LinuxCncDrive::repeated_samples() const noexcept {
  return impl_->stream ? impl_->stream->repeated() : 0;
}
std::uint64_t LinuxCncDrive::samples() const noexcept {
  return impl_->stream ? impl_->stream->records() - impl_->drained : 0;
}
std::string LinuxCncDrive::last_program_path() const { return impl_->last_path; }
int LinuxCncDrive::backlog() const noexcept { return impl_->stream ? impl_->stream->backlog() : 0; }

}  // namespace smc::edge
