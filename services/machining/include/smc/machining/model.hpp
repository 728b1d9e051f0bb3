#pragma once
// The milling model: cutter, part, cutting-force law and structure, as plain
// data. Everything the time-domain simulation and the stability analysis
// need; nothing of any particular case is in the code (the paper's case is
// data: cell/models/paper_face_mill.textproto, see paper_case.hpp).
//
// Units are in the names. Lengths in mm, forces in N, time in s, speeds in
// rpm, angles in degrees where the configuration document has degrees (the
// lead angle) and radians elsewhere. The structs mirror smc.config.MillingModel
// field by field (model_proto.hpp converts), so a field path in an error
// message is the document's path.
//
// Frame (top view, looking down the spindle axis onto the part):
//
//        +y ^
//           |        part band: y in [offset - width/2, offset + width/2]
//           |        part along the feed: x in [0, length]
//     tooth |  theta
//        \  | /
//         \ |/  theta measured from +x towards +y
//   --------O--------> +x  feed (the cutter moves +x relative to the part)
//           |
//  +z points from the part up the spindle; F_z > 0 pushes the tool up.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace smc::machining {

// Evenly spaced teeth on a face mill or end mill.
struct Cutter {
  int teeth = 0;              // >= 1
  double radius_mm = 0;       // R_f, > 0
  double lead_angle_deg = 0;  // psi_r in [0, 90): 0 = square shoulder (no axial thrust)
  // Radial runout per tooth (um): tooth i's edge at radius_mm + r_i / 1000.
  // Empty (the default) or one value per tooth, each |r_i| <= kMaxRunoutUm.
  // README.md, "Runout".
  std::vector<double> radial_runout_um;
};

inline constexpr double kMaxRunoutUm = 1000;

// True when some tooth has a non-zero runout.
bool has_runout(const Cutter& cutter) noexcept;

// The runout of a cutter whose axis is off the spindle's by amplitude_um,
// the offset pointing phase_deg from tooth 0: r_i = e cos(2 pi i / teeth -
// phase). Throws std::invalid_argument for teeth < 1 or a non-finite value.
std::vector<double> eccentric_runout_um(int teeth, double amplitude_um, double phase_deg = 0);

// The static chip of tooth i at angle theta with runout (mm), before the
// structure's vibration: the material left by the tooth that cut deepest
// before it, min over j = 1..teeth of (j f_t cos(theta) + r_i - r_(i-j)),
// r in mm (kinematics of Kline and DeVor: a tooth that cuts nothing leaves
// its share to the next). Equals f_t cos(theta) without runout.
inline double runout_chip_mm(const double* r_mm, int teeth, int tooth, double feed_mm,
                             double cos_theta) noexcept {
  double chip = feed_mm * cos_theta + r_mm[tooth] - r_mm[(tooth + teeth - 1) % teeth];
  for (int j = 2; j <= teeth; ++j) {
    const double c = j * feed_mm * cos_theta + r_mm[tooth] - r_mm[(tooth + teeth - j) % teeth];
    if (c < chip) chip = c;
  }
  return chip;
}

// Where the part sits under the cutter (see the frame above).
struct Workpiece {
  double width_mm = 0;   // across the feed, > 0
  double offset_mm = 0;  // centre line of the part from the cutter axis, along y
  double length_mm = 0;  // along the feed, > 0
  // Spindle sense relative to the part. false: the teeth enter the material on
  // the side of the part's centre line (up-milling side first: the chip grows
  // from the entry); true: they leave it there (down-milling). For a part
  // centred under the cutter (offset 0) false means theta increases with time.
  // rotation_sense() in cutting.hpp gives the resulting sense.
  bool down_milling = false;
};

// P = coefficient * f^feed_exponent * d^depth_exponent * (V/1000)^speed_exponent
// with P in kN/mm^2, f (chip) and d (depth) in mm, V (cutting speed) in m/min:
// the paper's A1 and A2. The force is P * f * d (kN).
struct PressureLaw {
  double coefficient_kn_per_mm2 = 0;  // > 0
  double feed_exponent = 0;           // > -1 (the force P f d must vanish with the chip)
  double depth_exponent = 0;          // > -1
  double speed_exponent = 0;
};

// The paper's power-law pressures: cutting (tangential, P_C) and thrust (P_T,
// normal to the cutting edge; cos(psi_r) of it is radial, sin(psi_r) axial).
struct PowerLaw {
  PressureLaw cutting;
  PressureLaw thrust;
};

// The linear law most stability literature uses: F_t = K_t a h, F_n = K_n a h
// (a depth, h chip), F_a = K_a a h. F_n is the thrust normal to the edge, split
// by the lead angle like the power law's thrust; F_a adds to the axial force.
struct LinearLaw {
  double k_t_n_per_mm2 = 0;  // > 0
  double k_n_n_per_mm2 = 0;  // >= 0
  double k_a_n_per_mm2 = 0;  // >= 0 (0 if unknown)
};

using CuttingLaw = std::variant<PowerLaw, LinearLaw>;

// One structural mode: q'' + 2 zeta omega q' + omega^2 q = (omega^2 / k) F,
// q in mm, F in N. Its static deflection is F / k.
struct Mode {
  double natural_frequency_rad_s = 0;  // omega > 0
  double damping_ratio = 0;            // zeta in (0, 1)
  double stiffness_n_per_mm = 0;       // k > 0
};

// Modes of the tool and of the part along x and y; any number per axis (none:
// rigid along that axis). The tool is displaced by the cutting force on the
// tool, the part by its reaction (the opposite force).
struct Structure {
  std::vector<Mode> tool_x;
  std::vector<Mode> tool_y;
  std::vector<Mode> part_x;
  std::vector<Mode> part_y;
};

// The regenerative delay: the time since the surface now being cut was left.
// With evenly spaced teeth that is the tooth period (default); the paper's
// text says one revolution, which is kept as an option.
enum class DelayKind : std::uint8_t { tooth_period, spindle_revolution };

enum class Provenance : std::uint8_t { unspecified, handbook, fitted, identified };

// A cut: what tools use when none is given.
struct ReferenceCut {
  double depth_mm = 0;
  double feedrate_mm_s = 0;
  double spindle_rpm = 0;
};

inline constexpr double kDefaultInternalStepS = 1e-5;
inline constexpr double kMaxInternalStepS = 1e-4;
// Below this a tooth period is millions of steps: nothing to learn, only time lost.
inline constexpr double kMinInternalStepS = 1e-7;

struct MillingModel {
  std::string name;
  Cutter cutter;
  Workpiece workpiece;
  CuttingLaw law;
  Structure structure;
  DelayKind delay = DelayKind::tooth_period;
  double internal_step_s = kDefaultInternalStepS;  // [1e-7, 1e-4]
  Provenance provenance = Provenance::unspecified;
  bool validated = false;
  std::optional<ReferenceCut> reference_cut;
};

// Operating conditions of one cut (constant over a batch run).
struct CutConditions {
  double spindle_rpm = 0;        // > 0
  double feed_per_tooth_mm = 0;  // >= 0
  double depth_mm = 0;           // >= 0
};

// f_t = feedrate / (teeth * rev/s). 0 when the spindle is stopped.
double feed_per_tooth_mm(double feedrate_mm_s, double spindle_rpm, int teeth) noexcept;
// Tooth period (s) and spindle revolution (s).
double tooth_period_s(double spindle_rpm, int teeth) noexcept;
// The regenerative delay (s) of `model` at `spindle_rpm`.
double delay_s(const MillingModel& model, double spindle_rpm) noexcept;

// Every problem found, each as "path: what is wrong, got value"; what() is
// all of them, one per line.
class ModelError : public std::invalid_argument {
 public:
  explicit ModelError(std::vector<std::string> errors);
  const std::vector<std::string>& errors() const noexcept { return errors_; }

 private:
  std::vector<std::string> errors_;
};

// Checks every range; throws ModelError naming each bad field as
// "<prefix>.structure.tool_x[0].damping_ratio: must be in (0, 1), got 1.7".
void validate(const MillingModel& model, const std::string& prefix = "milling_model");
// The same as a list (empty: valid).
std::vector<std::string> validation_errors(const MillingModel& model,
                                           const std::string& prefix = "milling_model");
// Checks a cut against a model: rpm > 0 and finite, feed and depth >= 0 and
// finite. Throws std::invalid_argument naming the field.
void validate(const CutConditions& cut);

// Total number of modes in a structure.
std::size_t mode_count(const Structure& structure) noexcept;

}  // namespace smc::machining
