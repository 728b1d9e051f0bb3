#pragma once
// The simulated mill: a Drive that machines a part in the time-domain model
// of services/machining (forces A1–A5 and the axial force, structural modes,
// regenerative chip), with the part's surface tracked along the feed so that
// contact starts and ends where the cutter meets and leaves material, the
// program's passes executed in turn (rapid repositioning in air between
// them), feed and feed hold applied, and the force sensor modelled (anti-alias
// low-pass per channel, white noise with a fixed seed).
//
// Real-time contract: step() and rewrite() do not allocate, lock, log or
// throw (the simulator's buffers are sized at construction for
// min_spindle_rpm). Deterministic for a given seed.

#include <memory>
#include <vector>

#include "smc/edge/drive.hpp"

namespace smc::config {
class MillingModel;
class SimulatedMill;
class SupervisorConfig;
}  // namespace smc::config

namespace smc::edge {

// A plant that is not the model: `plant`'s structure and cutting law in
// place of `configured`'s, keeping the configured cutter and workpiece (the
// job's geometry) where `configured` has them. `smc-edge run --mill-model`
// and `smc-edge simulate --mill-model` simulate their mill this way.
void use_plant_model(smc::config::MillingModel& configured, smc::config::MillingModel plant);

// Throws ConfigError when module E will read the wideband channel (it runs
// with a structure in y) at another count of samples a period than the
// simulated mill gives it (operation.wideband_samples_per_tick against
// simulation.f_y_wide_samples_per_tick): E would hold the feed at the
// first sample in contact, so such a configuration is refused before it
// runs. Where E judges S alone it never reads the channel.
void check_wideband_channel_agrees(const smc::config::SupervisorConfig& cfg);

class SimulatedMill final : public Drive {
 public:
  // Not real-time. Throws ConfigError naming the field for a bad model.
  SimulatedMill(const smc::config::MillingModel& model, const smc::config::SimulatedMill& sim,
                double sample_period_s);
  ~SimulatedMill() override;

  void load(const FixedProgram& program) override;
  Status step(double feedrate_cmd_mm_s, DriveSample& out) noexcept override;
  Status rewrite(const FixedProgram& program, int from) noexcept override;
  double sample_period_s() const noexcept override { return period_s_; }
  // The spindle moves to a new speed at simulation.spindle_accel_rpm_s.
  bool can_change_spindle_speed() const noexcept override { return true; }
  Status change_spindle_speed(double rpm) noexcept override;
  bool can_retract() const noexcept override { return true; }
  Status retract() noexcept override;

  // Depth of material still above the final surface at x (mm), for tests.
  double remaining_depth_at(double x_mm) const noexcept;
  double part_length_mm() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double period_s_;
};

}  // namespace smc::edge
