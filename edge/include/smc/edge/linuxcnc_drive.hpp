#pragma once
// The LinuxCNC drive: the edge drives a real CNC control, LinuxCNC 2.9,
// through HAL and its task's NML channels (deploy/linuxcnc/README.md).
//
//   load()     not real-time: checks the machine (LinuxCNC running, out of
//              E-stop, on, homed, idle), renders the program as G-code
//              (services/supervision/gcode.hpp) into the program folder,
//              opens it in LinuxCNC (a program LinuxCNC refuses fails here,
//              with LinuxCNC's message), joins HAL as the machine id with
//              the feed held, and hands the control thread the start.
//   step()     real-time: one servo record of the sampler stream (forces,
//              spindle, positions, path velocity, program line) per call;
//              the feed command becomes motion.adaptive-feed (the share of
//              min(F, the axes' max velocity)), a command of 0 the
//              feed-inhibit; the heartbeat keeps smc-edge.hal's watchdog
//              from holding the feed.
//   rewrite()  real-time: holds the feed and asks the control thread to
//              hand LinuxCNC the remainder at a safe point: motion stopped,
//              program aborted (which stops LinuxCNC's spindle), the
//              spindle started again at the remainder's speed and the tool
//              lifted to the safe Z in one MDI line (the feed released for
//              that move only), then the remainder's G-code opened and run.
//   retract()  real-time: after a broken tool (module N), holds the feed and
//              asks the control thread to lift the tool clear: motion
//              stopped, program aborted, then a rapid to the programs' safe
//              Z in MDI (the feed released for that move only).
//   change_spindle_speed()  real-time: asks the control thread to set
//              LinuxCNC's spindle override to the new speed over the
//              program's (module O; reset to 1 at the job's start and when
//              a rewrite's remainder, which carries the new speed, runs).
//
// Pacing: the edge's loop runs once per servo record (wait_sample()), so it
// runs in step with LinuxCNC's servo thread rather than with its own clock.
// A record that does not come within stale_after_s, LinuxCNC leaving auto
// mode, E-stop, machine off, or a program error is a fault: the drive holds
// the feed (feed-inhibit, adaptive feed 0), step() returns kError from then
// on (the core's drive fault: feed hold) and fault() names the cause.

#include <chrono>
#include <memory>
#include <string>

#include "smc/edge/drive.hpp"

namespace smc::config {
class SupervisorConfig;
}

namespace smc::edge {

struct LinuxCncDriveOptions {
  std::string machine_id;  // the HAL component's name
  std::string nml_file = "/usr/share/linuxcnc/linuxcnc.nml";
  // Where the programs are written (must be readable by LinuxCNC's user).
  std::string program_dir = "/tmp/smc-programs";
  // No servo record for this long: a fault. 250 ms, like smc-edge.hal's
  // watchdog, for LinuxCNC's POSIX threads on a shared non-realtime machine
  // (its servo thread was seen to stall past 50 ms under load); about 50 ms
  // on a realtime kernel.
  double stale_after_s = 0.25;
};

class LinuxCncDrive final : public Drive {
 public:
  // Not real-time. Throws std::runtime_error when the edge is built without
  // LinuxCNC or LinuxCNC cannot be reached.
  LinuxCncDrive(const smc::config::SupervisorConfig& config, double sample_period_s,
                LinuxCncDriveOptions options);
  ~LinuxCncDrive() override;

  void load(const FixedProgram& program) override;
  Status step(double feedrate_cmd_mm_s, DriveSample& out) noexcept override;
  Status rewrite(const FixedProgram& program, int from) noexcept override;
  // Module O's speed change: LinuxCNC's spindle override, set by the
  // control thread (a hand-over like rewrite's; real-time here).
  bool can_change_spindle_speed() const noexcept override { return true; }
  Status change_spindle_speed(double rpm) noexcept override;
  double sample_period_s() const noexcept override { return period_s_; }
  // After a breakage: the tool lifted to the safe Z by the control thread
  // (LinuxCNC's MDI). kOk when asked; the lift follows within about a
  // second (a lift that fails is a fault: fault() names it).
  bool can_retract() const noexcept override { return true; }
  Status retract() noexcept override;

  // The loop's pacing: true once a servo record waits, false after the
  // stale time (the tick that follows then holds the feed: a stale fault).
  // A tick never runs on a record it has already had.
  bool wait_sample() noexcept;
  // Not real-time: the fault's cause, empty while there is none.
  std::string fault() const;
  // Servo records lost or repeated (the sampler's numbering), and read.
  std::uint64_t lost_samples() const noexcept;
  std::uint64_t repeated_samples() const noexcept;
  std::uint64_t samples() const noexcept;
  // Servo records waiting to be read now.
  int backlog() const noexcept;
  // The G-code of the last program handed to LinuxCNC.
  std::string last_program_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double period_s_;
};

}  // namespace smc::edge
