// The LinuxCNC drive of an edge built without LinuxCNC's development files:
// it cannot be made (the constructor says why and how to get it); the other
// members are never reached.
#include <stdexcept>

#include "smc/edge/linuxcnc_drive.hpp"

namespace smc::edge {

struct LinuxCncDrive::Impl {};

LinuxCncDrive::LinuxCncDrive(const smc::config::SupervisorConfig&, double sample_period_s,
                             LinuxCncDriveOptions)
    : period_s_(sample_period_s) {
  throw std::runtime_error(
      "this edge was built without LinuxCNC: install linuxcnc-uspace-dev (deploy/setup.sh) "
      "and build again");
}
LinuxCncDrive::~LinuxCncDrive() = default;
void LinuxCncDrive::load(const FixedProgram&) {}
Status LinuxCncDrive::step(double, DriveSample&) noexcept { return Status::kError; }
Status LinuxCncDrive::rewrite(const FixedProgram&, int) noexcept { return Status::kError; }
Status LinuxCncDrive::change_spindle_speed(double) noexcept { return Status::kError; }
Status LinuxCncDrive::retract() noexcept { return Status::kError; }
bool LinuxCncDrive::wait_sample() noexcept { return false; }
std::string LinuxCncDrive::fault() const { return "built without LinuxCNC"; }
std::uint64_t LinuxCncDrive::lost_samples() const noexcept { return 0; }
std::uint64_t LinuxCncDrive::repeated_samples() const noexcept { return 0; }
std::uint64_t LinuxCncDrive::samples() const noexcept { return 0; }
std::string LinuxCncDrive::last_program_path() const { return {}; }
int LinuxCncDrive::backlog() const noexcept { return 0; }

}  // namespace smc::edge
