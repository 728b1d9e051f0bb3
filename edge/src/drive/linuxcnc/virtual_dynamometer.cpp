// smc_dyno: the virtual dynamometer, a LinuxCNC realtime HAL component.
//
// It cuts the simulated part with LinuxCNC's own motion: every servo period
// it takes the tool's actual position (joint feedback X, Z) and the spindle's
// actual speed, steps the time-domain milling model of services/machining
// (forces A1-A5 and the axial force, the structure's modes, the regenerative
// chip) over that period, and writes the force a dynamometer would read to
// its pins, through the same anti-alias filters and noise as the simulated
// mill's sensor (F_y also a second time through the wideband channel's
// filter, for module E's vibration estimate). Run it in the servo thread
// before the edge's sampler: the force the edge reads in a period is that of
// the motion of the same period.
//
// The part: the configuration's workpiece (X0 its leading edge, Y0 the
// cutter axis, Z0 its top face; deploy/linuxcnc/README.md), a fresh blank
// at load and at each rising edge of `new-part`. The material the cutter's
// footprint sweeps stands at the tool's Z from then on, so the depth of cut
// comes from where LinuxCNC actually put the tool, whatever the program.
// A new part is mounted with the tool clear of it: until the tool has been
// at or above the top face since `new-part` (a job stopped mid-cut leaves it
// in the old part; the next program's first move lifts it), the tool cuts
// nothing and leaves the blank whole.
//
//   loadrt smc_dyno config=FILE [plant=FILE] [seed=N]
//     config  a smc.config.SupervisorConfig (text format): its milling_model
//             and simulation (sensor cut-offs, noise) -- the same file as
//             `smc-edge simulate --config FILE`
//     plant   a smc.config.MillingModel whose structure and cutting law
//             replace the configuration's (a mill that is not the model),
//             like `smc-edge simulate --mill-model FILE`
//   addf smc-dyno.update servo-thread   (before sampler.0)
//
// Pins (component smc_dyno, pins smc-dyno.*):
//   in  float x-mm, z-mm       tool position (joint feedback)
//   in  float spindle-rps      spindle speed (rev/s)
//   in  bit   new-part         rising edge: a fresh blank
//   in  s32   break-tooth      set to a tooth (1-based): that tooth loses its
//                              edge from this period on (as the simulated
//                              mill's simulation.tooth_breaks); 0: none
//   in  float break-after-s    the break waits until the cutter has been
//                              in the part this long (machine time, from
//                              the first tooth in the blank mounted last):
//                              a test sets it before the job, so the break
//                              lands where it means, whatever the load on
//                              the host; 0: at once
//   out float force-x/y/z      force on the tool (N), filtered, with noise
//   out float force-y-wide     F_y through the wideband filter
//                              (simulation.f_y_wide_cutoff_hz and
//                              f_y_wide_order), with noise
//                              from a stream of its own (the simulated mill's
//                              f_y_wide_n)
//   out float force-y-wide-sub.0-3
//                              where the wideband channel samples faster
//                              than the servo period
//                              (simulation.f_y_wide_samples_per_tick, at
//                              most 5 here: the sampler has 21 pins), the
//                              period's earlier samples of it, oldest first
//                              (force-y-wide is the last); else 0
//   out s32   wide-samples     the channel's samples this period (1-5)
//   out bit   wideband         true: this sensor has the wideband F_y channel
//   out float vibration-y-mm   the tool's vibration relative to the part in
//                              y (mm), unfiltered and without noise: what
//                              labels chatter independently of module E
//                              (the simulated mill's vibration_y_mm; a
//                              machine has no such signal)
//   out bit   vibration        true: vibration-y-mm is driven
//   out float power-w          spindle (cutting) power at the sample instant
//   out float depth-mm         depth of cut at the cutter's leading edge
//   out s32   teeth-in-cut
//   out u32   status           the simulator's StepStatus bits; bit 8: the
//                              servo period is not the model's sample period
//   out u32   samples          periods stepped
//
// Real-time contract: rtapi_app_main() reads the files and allocates; the
// update function never allocates, locks or blocks.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "smc/documents/load.hpp"
#include "smc/machining/anti_alias.hpp"
#include "smc/machining/model_proto.hpp"
#include "smc/machining/simulator.hpp"
#include "smc_config.pb.h"

extern "C" {
#include <hal.h>
#include <rtapi.h>
#include <rtapi_app.h>

// NOLINTBEGIN: the module parameters are C globals that rtapi_app sets by name.
static char* config = nullptr;
static char* plant = nullptr;
static int seed = 1;
RTAPI_MP_STRING(config, "smc.config.SupervisorConfig (text format): milling_model, simulation")
RTAPI_MP_STRING(plant, "smc.config.MillingModel replacing the structure and cutting law")
RTAPI_MP_INT(seed, "noise seed")
// NOLINTEND
}

namespace {

namespace mc = smc::machining;

constexpr unsigned kPeriodMismatch = 1u << 8;
// The wideband channel's samples a servo period at most: the last on
// force-y-wide, the others on force-y-wide-sub.0-3.
constexpr unsigned kMaxWidePerTick = 5;

struct Pins {
  hal_float_t* x_mm;
  hal_float_t* z_mm;
  hal_float_t* spindle_rps;
  hal_bit_t* new_part;
  hal_s32_t* break_tooth;
  hal_float_t* break_after_s;
  hal_float_t* force_x;
  hal_float_t* force_y;
  hal_float_t* force_z;
  hal_float_t* force_y_wide;
  hal_float_t* force_y_wide_sub[4];
  hal_s32_t* wide_samples;
  hal_bit_t* wideband;
  hal_float_t* vibration_y_mm;
  hal_bit_t* vibration;
  hal_float_t* power_w;
  hal_float_t* depth_mm;
  hal_s32_t* teeth_in_cut;
  hal_u32_t* status;
  hal_u32_t* samples;
};

struct Dyno {
  mc::MillingModel model;
  mc::MillSimulator sim;
  std::vector<double> trace_x, trace_y, trace_z;
  mc::AntiAliasLowPass lp_x, lp_y, lp_z, lp_y_wide;
  // The wideband channel's filter output is sampled every `wide_stride`
  // internal steps (all of a period's: once a period).
  std::size_t wide_stride = 1;
  std::mt19937_64 rng;
  std::normal_distribution<double> noise{0.0, 1.0};
  // The wideband channel's noise has a stream of its own, so that the
  // other channels' noise is what it was before the channel existed.
  std::mt19937_64 rng_wide;
  std::normal_distribution<double> noise_wide{0.0, 1.0};
  double noise_rms_n = 0;
  // Depth already removed, per bin along the part (mm below the top face).
  std::vector<double> removed;
  double bin_mm = 0.25;
  double last_x = 0;
  bool have_x = false;
  bool last_new_part = false;
  bool clear_of_part = true;  // the tool was above the top face since the blank was mounted
  // The material's level (mm removed below the top face) the leading edge
  // met last inside the part: read while the cutter leaves it.
  double exit_level = 0;
  int broken_tooth = 0;  // the last tooth broken by the break-tooth pin
  double cut_s = -1;     // since the first tooth met this blank (-1: not yet)
  long period_ns = 0;

  Dyno(mc::MillingModel m, const mc::SimulatorOptions& o) : model(std::move(m)), sim(model, o) {}

  double length() const noexcept { return model.workpiece.length_mm; }
  double radius() const noexcept { return model.cutter.radius_mm; }
  double removed_at(double x) const noexcept {
    if (x < 0 || x > length()) return 1e9;  // no material outside the part
    const auto i = static_cast<std::size_t>(
        std::min<double>(x / bin_mm, static_cast<double>(removed.size() - 1)));
    return removed[i];
  }
  void fresh_blank() noexcept {
    std::fill(removed.begin(), removed.end(), 0.0);
    exit_level = 0;
    sim.reset();
    lp_x.reset();
    lp_y.reset();
    lp_z.reset();
    lp_y_wide.reset();
    have_x = false;
    clear_of_part = false;
    cut_s = -1;
  }
};

Dyno* g_dyno = nullptr;
Pins* g_pins = nullptr;
int g_comp = -1;

std::unique_ptr<Dyno> make_dyno() {
  if (config == nullptr || *config == '\0') {
    throw std::runtime_error(
        "config=FILE is required (a SupervisorConfig, e.g. "
        "edge/configs/smc2.textproto)");
  }
  // Its milling_model_file and grafcet_file resolved, as smc-edge reads it.
  const auto cfg = smc::documents::load_supervisor_config(config);
  if (!cfg.has_milling_model()) {
    throw std::runtime_error(std::string(config) + ": milling_model: missing");
  }
  smc::config::MillingModel mm = cfg.milling_model();
  if (plant != nullptr && *plant != '\0') {
    smc::config::MillingModel p;
    smc::documents::load(plant, p);
    // The plant's structure and cutting law; the configuration's cutter and part.
    if (mm.has_cutter()) *p.mutable_cutter() = mm.cutter();
    if (mm.has_workpiece()) *p.mutable_workpiece() = mm.workpiece();
    mm = std::move(p);
  }
  mc::MillingModel model = mc::from_proto(mm, "milling_model");
  const auto& s = cfg.simulation();
  if (const auto order = s.f_y_wide_order(); !mc::AntiAliasLowPass::is_order(order)) {
    throw std::runtime_error(std::string(config) + ": simulation.f_y_wide_order: must be even, " +
                             "2-8 (got " + std::to_string(order) + "); fix: 0 or 2, e.g. 8");
  }
  const double period_s = 0.5e-3;  // the servo period the shipped INI sets
  mc::SimulatorOptions so;
  so.sample_period_s = period_s;
  so.max_internal_step_s =
      period_s / std::max(1.0, std::ceil(period_s / model.internal_step_s - 1e-9));
  so.min_spindle_rpm = s.min_spindle_rpm() > 0 ? s.min_spindle_rpm() : 100;
  so.forces_at_sample_instant = false;
  auto d = std::make_unique<Dyno>(std::move(model), so);
  const auto steps = static_cast<std::size_t>(d->sim.steps_per_sample());
  d->trace_x.assign(steps, 0.0);
  d->trace_y.assign(steps, 0.0);
  d->trace_z.assign(steps, 0.0);
  const auto per_tick = s.f_y_wide_samples_per_tick() == 0 ? 1U : s.f_y_wide_samples_per_tick();
  if (per_tick > kMaxWidePerTick || steps % per_tick != 0) {
    throw std::runtime_error(std::string(config) +
                             ": simulation.f_y_wide_samples_per_tick: " + std::to_string(per_tick) +
                             " samples do not divide the " + std::to_string(steps) +
                             " internal steps of a servo period evenly (at most 5 here: the "
                             "sampler's pins); fix: 0 or 1, 2 or 5");
  }
  d->wide_stride = steps / per_tick;
  const double rate = 1.0 / d->sim.internal_step_s();
  d->lp_x.configure(s.f_y_cutoff_hz(), rate);
  d->lp_y.configure(s.f_y_cutoff_hz(), rate);
  d->lp_z.configure(s.f_z_cutoff_hz(), rate);
  d->lp_y_wide.configure(s.f_y_wide_cutoff_hz() > 0 ? s.f_y_wide_cutoff_hz() : s.f_z_cutoff_hz(),
                         rate, s.f_y_wide_order() > 0 ? static_cast<int>(s.f_y_wide_order()) : 2);
  d->noise_rms_n = std::max(0.0, s.noise_rms_n());
  d->rng.seed(static_cast<std::uint64_t>(seed));
  // Derived from the seed and different from it, as the simulated mill's.
  d->rng_wide.seed(static_cast<std::mt19937_64::result_type>(seed) ^
                   std::mt19937_64::result_type{0x9e3779b97f4a7c15});
  d->removed.assign(static_cast<std::size_t>(std::ceil(d->length() / d->bin_mm)) + 1, 0.0);
  d->period_ns = static_cast<long>(std::lround(period_s * 1e9));
  return d;
}

void update(void* /*arg*/, long period) {
  Dyno& d = *g_dyno;
  Pins& p = *g_pins;
  unsigned status = 0;
  if (std::labs(period - d.period_ns) > d.period_ns / 10) status |= kPeriodMismatch;
  const bool np = *p.new_part;
  if (np && !d.last_new_part) d.fresh_blank();
  d.last_new_part = np;
  // A tooth set on break-tooth loses its edge (1 mm back, as a lost edge in
  // the simulated mill), once per setting.
  // With break-after-s it waits for that much of the cut.
  const int tooth = *p.break_tooth;
  const bool real_tooth = tooth >= 1 && tooth <= d.model.cutter.teeth;
  const double wait_s = *p.break_after_s;
  const bool due = !(wait_s > 0) || (d.cut_s >= 0 && d.cut_s >= wait_s);
  if (tooth != d.broken_tooth && (!real_tooth || due)) {
    if (real_tooth) d.sim.set_tooth_runout_mm(tooth - 1, d.sim.tooth_runout_mm(tooth - 1) - 1.0);
    d.broken_tooth = tooth;
  }

  const double x = *p.x_mm;
  const double z = *p.z_mm;
  const double dt = d.sim.sample_period_s();
  mc::SampleInput in;
  in.spindle_rpm = std::max(0.0, static_cast<double>(*p.spindle_rps) * 60.0);
  if (d.have_x && std::isfinite(x)) {
    // Along the feed (+X) the simulator moves the cutter itself over the
    // period (the chip follows the feed); anything else is a jump in air.
    const double v = (x - d.last_x) / dt;
    in.feedrate_mm_s = v > 0 ? v : 0.0;
    d.sim.set_tool_position(v > 0 ? d.last_x : x);
  } else {
    d.sim.set_tool_position(x);
  }
  d.last_x = x;
  d.have_x = std::isfinite(x);
  // The chip depth where the leading edge meets material. Once the leading
  // edge is past the part's end no new material meets it, but the teeth
  // still cut the material left ahead of them until their tips pass the
  // end (the simulator ends the cut there, as the simulated mill's): the
  // level the leading edge met last holds. (The bins behind the leading
  // edge are marked cut below, the last one too, which read as no material
  // at all and ended every exit as the leading edge passed the part's end,
  // the cutter's radius early.)
  const double lead = x + d.radius();
  if (!(lead >= d.length())) d.exit_level = d.removed_at(std::max(0.0, lead));
  const double tip = -z;  // below the top face
  if (!d.clear_of_part && std::isfinite(tip) && tip <= 0) d.clear_of_part = true;
  in.depth_mm = std::isfinite(tip) && d.clear_of_part ? std::max(0.0, tip - d.exit_level) : 0;
  mc::Sample smp;
  status |= d.sim.step(in, smp, {d.trace_x.data(), d.trace_y.data(), d.trace_z.data()});
  double fx = 0, fy = 0, fz = 0, fy_wide = 0;
  double wide[kMaxWidePerTick] = {};
  int wide_n = 0;
  for (std::size_t k = 0; k < d.trace_x.size(); ++k) {
    fx = d.lp_x(d.trace_x[k]);
    fy = d.lp_y(d.trace_y[k]);
    fz = d.lp_z(d.trace_z[k]);
    fy_wide = d.lp_y_wide(d.trace_y[k]);
    if ((k + 1) % d.wide_stride == 0) wide[wide_n++] = fy_wide;
  }
  if (d.noise_rms_n > 0) {
    fx += d.noise_rms_n * d.noise(d.rng);
    fy += d.noise_rms_n * d.noise(d.rng);
    fz += d.noise_rms_n * d.noise(d.rng);
    for (int i = 0; i < wide_n; ++i) wide[i] += d.noise_rms_n * d.noise_wide(d.rng_wide);
  }
  fy_wide = wide[wide_n - 1];
  // The cutter's footprint behind its leading edge now stands at the tool's
  // Z: every bin [i, i+1) x bin_mm wholly behind the leading edge (the bin
  // under the edge is where the next chip's depth is read).
  if (d.clear_of_part && std::isfinite(tip) && tip > 0 && std::isfinite(x)) {
    auto i = static_cast<std::size_t>(std::max(0.0, x - d.radius()) / d.bin_mm);
    for (; i < d.removed.size() && static_cast<double>(i + 1) * d.bin_mm <= lead; ++i) {
      d.removed[i] = std::max(d.removed[i], tip);
    }
  }
  *p.force_x = fx;
  *p.force_y = fy;
  *p.force_z = fz;
  *p.force_y_wide = fy_wide;
  for (int i = 0; i < 4; ++i) *p.force_y_wide_sub[i] = i < wide_n - 1 ? wide[i] : 0.0;
  *p.wide_samples = wide_n;
  *p.wideband = true;
  *p.vibration_y_mm = smp.tool_y_mm - smp.part_y_mm;
  *p.vibration = true;
  *p.power_w = smp.power_w;
  *p.depth_mm = in.depth_mm;
  *p.teeth_in_cut = smp.teeth_in_cut;
  if (d.cut_s >= 0) {
    d.cut_s += dt;
  } else if (smp.teeth_in_cut > 0) {
    d.cut_s = 0;
  }
  *p.status = status;
  *p.samples = *p.samples + 1;
}

int make_pins(int comp) {
  g_pins = static_cast<Pins*>(hal_malloc(sizeof(Pins)));
  if (g_pins == nullptr) return -1;
  Pins& p = *g_pins;
  int r = 0;
  r |= hal_pin_float_new("smc-dyno.x-mm", HAL_IN, &p.x_mm, comp);
  r |= hal_pin_float_new("smc-dyno.z-mm", HAL_IN, &p.z_mm, comp);
  r |= hal_pin_float_new("smc-dyno.spindle-rps", HAL_IN, &p.spindle_rps, comp);
  r |= hal_pin_bit_new("smc-dyno.new-part", HAL_IN, &p.new_part, comp);
  r |= hal_pin_s32_new("smc-dyno.break-tooth", HAL_IN, &p.break_tooth, comp);
  r |= hal_pin_float_new("smc-dyno.break-after-s", HAL_IN, &p.break_after_s, comp);
  r |= hal_pin_float_new("smc-dyno.force-x", HAL_OUT, &p.force_x, comp);
  r |= hal_pin_float_new("smc-dyno.force-y", HAL_OUT, &p.force_y, comp);
  r |= hal_pin_float_new("smc-dyno.force-z", HAL_OUT, &p.force_z, comp);
  r |= hal_pin_float_new("smc-dyno.force-y-wide", HAL_OUT, &p.force_y_wide, comp);
  for (int i = 0; i < 4; ++i) {
    r |= hal_pin_float_newf(HAL_OUT, &p.force_y_wide_sub[i], comp, "smc-dyno.force-y-wide-sub.%d",
                            i);
  }
  r |= hal_pin_s32_new("smc-dyno.wide-samples", HAL_OUT, &p.wide_samples, comp);
  r |= hal_pin_bit_new("smc-dyno.wideband", HAL_OUT, &p.wideband, comp);
  r |= hal_pin_float_new("smc-dyno.vibration-y-mm", HAL_OUT, &p.vibration_y_mm, comp);
  r |= hal_pin_bit_new("smc-dyno.vibration", HAL_OUT, &p.vibration, comp);
  r |= hal_pin_float_new("smc-dyno.power-w", HAL_OUT, &p.power_w, comp);
  r |= hal_pin_float_new("smc-dyno.depth-mm", HAL_OUT, &p.depth_mm, comp);
  r |= hal_pin_s32_new("smc-dyno.teeth-in-cut", HAL_OUT, &p.teeth_in_cut, comp);
  r |= hal_pin_u32_new("smc-dyno.status", HAL_OUT, &p.status, comp);
  r |= hal_pin_u32_new("smc-dyno.samples", HAL_OUT, &p.samples, comp);
  return r;
}

}  // namespace

extern "C" int rtapi_app_main(void) {
  g_comp = hal_init("smc_dyno");  // halcmd finds a module by its component
  if (g_comp < 0) return g_comp;
  try {
    g_dyno = make_dyno().release();
  } catch (const std::exception& e) {
    rtapi_print_msg(RTAPI_MSG_ERR, "smc_dyno: %s\n", e.what());
    hal_exit(g_comp);
    return -EINVAL;
  }
  if (make_pins(g_comp) != 0 ||
      hal_export_funct("smc-dyno.update", update, nullptr, 1, 0, g_comp) != 0) {
    rtapi_print_msg(RTAPI_MSG_ERR, "smc_dyno: cannot create its pins or function\n");
    delete g_dyno;
    g_dyno = nullptr;
    hal_exit(g_comp);
    return -EINVAL;
  }
  hal_ready(g_comp);
  return 0;
}

extern "C" void rtapi_app_exit(void) {
  hal_exit(g_comp);
  delete g_dyno;
  g_dyno = nullptr;
}
