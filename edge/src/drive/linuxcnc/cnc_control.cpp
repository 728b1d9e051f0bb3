#include "cnc_control.hpp"

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

// LinuxCNC's NML headers are old C++ that warns under our flags: included as
// system headers (CMake: -isystem).
#include <emc.hh>
#include <emc_nml.hh>
#include <nml.hh>
#include <nml_oi.hh>
#include <rcs.hh>
#include <rcs_print.hh>

namespace smc::edge::linuxcnc {

namespace {
constexpr auto kCommandTimeout = std::chrono::seconds(5);
constexpr auto kPoll = std::chrono::milliseconds(2);
}  // namespace

struct CncControl::Impl {
  std::unique_ptr<RCS_CMD_CHANNEL> cmd;
  std::unique_ptr<RCS_STAT_CHANNEL> stat;
  std::unique_ptr<NML> err;
  int serial = 0;

  const EMC_STAT* poll() {
    if (stat->peek() < 0) throw std::runtime_error("LinuxCNC's status channel failed");
    return stat->get_address() != nullptr && stat->get_address()->type == EMC_STAT_TYPE
               ? static_cast<const EMC_STAT*>(stat->get_address())
               : nullptr;
  }

  // Sends and waits until the task has received it and, with `finish`,
  // finished it (done or error), as LinuxCNC's own interfaces do. A program
  // run stays "executing" until the program ends: that one waits for receipt.
  void send(RCS_CMD_MSG& m, const char* what, bool finish = true) {
    if (cmd->write(&m) != 0) {
      throw std::runtime_error(std::string("LinuxCNC refused the command '") + what + "'");
    }
    serial = m.serial_number;
    const auto until = std::chrono::steady_clock::now() + kCommandTimeout;
    while (std::chrono::steady_clock::now() < until) {
      const EMC_STAT* s = poll();
      if (s != nullptr) {
        const int diff = s->echo_serial_number - serial;
        if (diff > 0 || (diff == 0 && !finish) ||
            (diff == 0 && (s->status == RCS_DONE || s->status == RCS_ERROR))) {
          if (diff == 0 && s->status == RCS_ERROR) {
            throw std::runtime_error(std::string("LinuxCNC: '") + what + "' failed");
          }
          return;
        }
      }
      std::this_thread::sleep_for(kPoll);
    }
    throw std::runtime_error(std::string("LinuxCNC did not complete '") + what + "' within 5 s");
  }
};

CncControl::CncControl(const std::string& nml_file) : impl_(std::make_unique<Impl>()) {
  set_rcs_print_destination(RCS_PRINT_TO_NULL);
  const char* f = nml_file.c_str();
  impl_->stat = std::make_unique<RCS_STAT_CHANNEL>(emcFormat, "emcStatus", "xemc", f);
  impl_->cmd = std::make_unique<RCS_CMD_CHANNEL>(emcFormat, "emcCommand", "xemc", f);
  impl_->err = std::make_unique<NML>(emcFormat, "emcError", "xemc", f);
  if (!impl_->stat->valid() || !impl_->cmd->valid() || !impl_->err->valid()) {
    throw std::runtime_error(
        "cannot reach LinuxCNC's task through " + nml_file +
        ": is LinuxCNC running? Start the headless mill with deploy/linuxcnc/run.sh start");
  }
}

CncControl::~CncControl() = default;

CncStatus CncControl::status() {
  const EMC_STAT* s = impl_->poll();
  CncStatus out;
  if (s == nullptr) return out;
  out.estop = s->task.state == EMC_TASK_STATE_ESTOP || s->task.state == EMC_TASK_STATE_ESTOP_RESET;
  out.on = s->task.state == EMC_TASK_STATE_ON;
  out.homed = true;
  for (int j = 0; j < s->motion.traj.joints; ++j) out.homed = out.homed && s->motion.joint[j].homed;
  out.auto_mode = s->task.mode == EMC_TASK_MODE_AUTO;
  out.manual_mode = s->task.mode == EMC_TASK_MODE_MANUAL;
  out.interp_idle = s->task.interpState == EMC_TASK_INTERP_IDLE;
  out.paused = s->task.interpState == EMC_TASK_INTERP_PAUSED;
  out.motion_line = s->task.motionLine;
  out.velocity_mm_s = s->motion.traj.current_vel;
  out.max_velocity_mm_s = s->motion.traj.maxVelocity;
  out.file = s->task.file;
  return out;
}

void CncControl::require_ready() {
  const CncStatus s = status();
  if (s.estop) {
    throw std::runtime_error(
        "LinuxCNC is in E-stop: release the E-stop and switch the machine on (the headless "
        "mill does both at start: deploy/linuxcnc/run.sh start)");
  }
  if (!s.on) throw std::runtime_error("LinuxCNC is off: switch the machine on");
  if (!s.homed) throw std::runtime_error("LinuxCNC is not homed: home every joint first");
  if (!s.interp_idle) {
    throw std::runtime_error("LinuxCNC is running a program already (" + s.file +
                             "): wait for it or abort it first");
  }
}

std::string CncControl::take_error_text() {
  std::string why;
  for (const auto& m : take_errors()) why += (why.empty() ? "" : "; ") + m;
  return why;
}

void CncControl::set_mode(int mode, const char* what) {
  EMC_TASK_SET_MODE m;
  m.mode = static_cast<decltype(m.mode)>(mode);
  impl_->send(m, what);
}

void CncControl::open_program(const std::string& path) {
  take_errors();  // only this program's messages
  set_mode(EMC_TASK_MODE_AUTO, "auto mode");
  EMC_TASK_PLAN_CLOSE close;
  impl_->send(close, "close the open program");
  EMC_TASK_PLAN_OPEN open;
  if (path.size() >= sizeof(open.file)) throw std::runtime_error(path + ": path too long");
  std::strncpy(open.file, path.c_str(), sizeof(open.file) - 1);
  try {
    impl_->send(open, "open the program");
  } catch (const std::runtime_error& e) {
    const std::string why = take_error_text();
    throw std::runtime_error(path + ": " + e.what() + (why.empty() ? "" : "; " + why));
  }
  const std::string why = take_error_text();
  if (!why.empty()) throw std::runtime_error(path + ": LinuxCNC: " + why);
}

void CncControl::run() {
  EMC_TASK_PLAN_RUN r;
  r.line = 0;
  impl_->send(r, "run the program", false);
}

void CncControl::abort() {
  EMC_TASK_ABORT a;
  impl_->send(a, "abort");
}

void CncControl::mdi(const std::string& line) {
  take_errors();  // only this command's messages
  set_mode(EMC_TASK_MODE_MDI, "MDI mode");
  EMC_TASK_PLAN_EXECUTE m;
  if (line.size() >= sizeof(m.command)) throw std::runtime_error(line + ": line too long");
  std::strncpy(m.command, line.c_str(), sizeof(m.command) - 1);
  // Waits for receipt only: the task stays "executing" while the move runs.
  impl_->send(m, "run an MDI line", false);
  const std::string why = take_error_text();
  if (!why.empty()) throw std::runtime_error("MDI '" + line + "': LinuxCNC: " + why);
}

void CncControl::set_spindle_override(double scale) {
  EMC_TRAJ_SET_SPINDLE_SCALE m;
  m.spindle = 0;
  m.scale = scale;
  // Waits for receipt only: while a program runs the task's status stays
  // "executing" until the program ends, as for run().
  impl_->send(m, "set the spindle override", false);
}

std::vector<std::string> CncControl::take_errors() {
  std::vector<std::string> out;
  for (;;) {
    const NMLTYPE type = impl_->err->read();
    if (type <= 0) break;
    const auto* a = impl_->err->get_address();
    // The messages' fixed char arrays, up to their first NUL.
    auto text = [](const char* t, std::size_t n) { return std::string(t, strnlen(t, n)); };
    switch (type) {
      case EMC_OPERATOR_ERROR_TYPE: {
        const auto* m = static_cast<const EMC_OPERATOR_ERROR*>(a);
        out.push_back(text(m->error, sizeof m->error));
        break;
      }
      case EMC_OPERATOR_TEXT_TYPE: {
        const auto* m = static_cast<const EMC_OPERATOR_TEXT*>(a);
        out.push_back(text(m->text, sizeof m->text));
        break;
      }
      case NML_ERROR_TYPE: {
        const auto* m = static_cast<const NML_ERROR*>(a);
        out.push_back(text(m->error, sizeof m->error));
        break;
      }
      case NML_TEXT_TYPE: {
        const auto* m = static_cast<const NML_TEXT*>(a);
        out.push_back(text(m->text, sizeof m->text));
        break;
      }
      default:
        out.push_back("message of type " + std::to_string(type));
    }
  }
  return out;
}

}  // namespace smc::edge::linuxcnc
