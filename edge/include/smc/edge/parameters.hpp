#pragma once
// The fixed machine and operation parameter modules (paper, design step 2),
// as the edge's modules read them. Built and validated from a
// smc.config.SupervisorConfig outside the loop.

#include <stdexcept>
#include <string>

namespace smc::config {
class SupervisorConfig;
}

namespace smc::edge {

// A configuration value out of range. what() names the field path, the
// value and the fix, e.g. "supervisor_config.operation.sample_period_s:
// must be > 0 (got 0); set the force sampling period, e.g. 0.0005".
struct ConfigError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct EdgeParameters {
  // Fixed machine parameters.
  double max_spindle_power_w = 0;
  double max_feedrate_mm_s = 0;
  double max_spindle_rpm = 0;
  // Fixed operation parameters.
  double max_feed_per_tooth_mm = 0;
  double min_feed_per_tooth_mm = 0;
  int teeth = 0;
  double cutter_radius_mm = 0;
  double sample_period_s = 0;
  double fast_period_s = 0;
  double slow_period_s = 0;
  double contact_threshold_n = 0;
  double force_reference_n = 0;  // 0: from the power limit and cutting speed
  double force_safety_factor = 1;
  double model_time_constant_s = 0;
  double adaptive_time_constant_s = 0;
  double rls_forgetting = 1;
  double adaptive_feed_exponent = 0;
  double chatter_threshold = 0;
  int chatter_confirm_revolutions = 1;
  double chatter_band_low_hz = 0;
  double chatter_band_high_hz = 0;
  double harmonic_guard_hz = 0;
  double chatter_min_rms_n = 0;
  double suppression_hold_s = 0;
  double force_sensor_range_n = 0;
  // Force-process model (eq. 1) for module L: F_Y[kN] = K d^beta f^alpha.
  bool has_force_model = false;
  double model_k_kn = 0;
  double model_beta = 0;
  double model_alpha = 0;

  // Derived, in samples.
  int samples_per_fast = 0;
  int samples_per_revolution = 0;
  int samples_per_hold = 0;

  // F_ref = P_max / V / safety, V the cutting speed at the periphery; or
  // the configured reference when one is given. Real-time safe.
  double force_reference_at(double spindle_rpm) const noexcept;
  // Feedrate (mm/s) for a feed per tooth at a spindle speed, and back.
  double feedrate_for(double feed_per_tooth_mm, double spindle_rpm) const noexcept;
  double feed_per_tooth_for(double feedrate_mm_s, double spindle_rpm) const noexcept;
};

// Reads and checks every field the modules use. `needs_force_model`: the
// configuration enables module L. Throws ConfigError naming the field.
EdgeParameters parameters_from_config(const smc::config::SupervisorConfig& cfg);

}  // namespace smc::edge
