#pragma once
// The edge's command channel to LinuxCNC's task (milltask): NML, the same
// channels LinuxCNC's own user interfaces use (emcCommand, emcStatus,
// emcError of the NML file; LinuxCNC 2.9's default
// /usr/share/linuxcnc/linuxcnc.nml). Only the LinuxCNC drive's control
// thread uses it, never the real-time loop.
//
// Not real-time: every call may block for up to the command timeout.
// Errors are std::runtime_error whose text names the cause and the fix.

#include <memory>
#include <string>
#include <vector>

namespace smc::edge::linuxcnc {

struct CncStatus {
  bool estop = false;  // E-stop active (or reset but not on)
  bool on = false;     // machine on
  bool homed = false;  // every joint homed
  bool auto_mode = false;
  bool manual_mode = false;
  bool interp_idle = true;  // no program running, paused or waiting
  bool paused = false;
  int motion_line = 0;  // line motion is executing
  double velocity_mm_s = 0;
  double max_velocity_mm_s = 0;  // the trajectory planner's limit
  std::string file;              // the open program
};

class CncControl {
 public:
  // Connects to the running LinuxCNC's NML channels. Throws when LinuxCNC
  // is not running (or runs with another NML file).
  explicit CncControl(const std::string& nml_file = "/usr/share/linuxcnc/linuxcnc.nml");
  ~CncControl();
  CncControl(const CncControl&) = delete;
  CncControl& operator=(const CncControl&) = delete;

  CncStatus status();
  // Throws naming what is missing when the machine cannot run a program:
  // in E-stop, off, not homed, or running a program already.
  void require_ready();
  // Auto mode, then opens `path` (closing any open program). Throws with
  // LinuxCNC's own messages when the program does not open.
  void open_program(const std::string& path);
  // Runs the open program from its first line.
  void run();
  // Stops the program and any motion (EMC_TASK_ABORT).
  void abort();
  // MDI mode, then runs one line of G-code; returns once LinuxCNC has
  // taken it (the motion may still run: status() tells when it stopped).
  // Throws with LinuxCNC's messages when it is refused.
  void mdi(const std::string& line);
  // The spindle override: the programmed speed times `scale`
  // (EMC_TRAJ_SET_SPINDLE_SCALE, spindle 0). It stays until changed, also
  // across programs.
  void set_spindle_override(double scale);
  // LinuxCNC's operator and NML error messages since the last call.
  std::vector<std::string> take_errors();

 private:
  // take_errors() joined with "; " (empty: none).
  std::string take_error_text();
  // Switches the task's mode (EMC_TASK_MODE_*), waiting until it is done.
  void set_mode(int mode, const char* what);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace smc::edge::linuxcnc
