#pragma once
// The edge's view of a LinuxCNC machine's servo thread: one record per servo
// period, lossless, through LinuxCNC's stock `sampler` realtime component
// (deploy/linuxcnc/smc-edge.hal loads it in the servo thread with the pins
// below, in this order). The edge joins HAL as a userspace component and
// reads the sampler's stream; a record it has not read waits in the stream
// (8192 deep: 4 s at 2 kHz), so a late loop loses nothing, and the sampler's
// own sample number tells a lost or repeated record.
//
// Real-time contract: the constructor and destructor talk to HAL and may
// throw; read() never allocates, locks or blocks.

#include <cstdint>
#include <string>

namespace smc::edge::linuxcnc {

// The sampler's pins, in order (its cfg string: kRecordTypes).
struct HalRecord {
  double fx_n = 0, fy_n = 0, fz_n = 0;  // smc-force-x/y/z: the dynamometer
  double spindle_rps = 0;               // spindle.0.speed-in (rev/s)
  double spindle_revs = 0;              // spindle.0.revs (encoder position, revolutions)
  double x_mm = 0, y_mm = 0, z_mm = 0;  // joint positions (feedback)
  double velocity_mm_s = 0;             // motion.current-vel (path speed)
  std::int32_t program_line = 0;        // motion.program-line
  double fy_wide_n = 0;                 // smc-force-y-wide: F_y through the wideband filter
  bool fy_wide_present = false;         // smc-force-y-wide-present: the sensor has that channel
  double vibration_y_mm = 0;            // smc-vibration-y: the tool's vibration (the virtual
  bool vibration_present = false;       // dynamometer's; smc-vibration-y-present: driven)
  double fy_wide_sub_n[4] = {};         // smc-force-y-wide-sub-0..3: the channel's earlier
  std::int32_t fy_wide_samples = 0;     // samples this period, of smc-force-y-wide-samples
  std::uint32_t sample_no = 0;          // the sampler's count
};

inline constexpr const char* kRecordTypes = "fffffffffsfbfbffffs";
// LinuxCNC 2.9's sampler stream key for channel 0 (rtapi_shmkeys.h,
// SAMPLER_SHMEM_KEY); channel n is key + n.
inline constexpr int kSamplerKey = 0x48534130;

class HalSampleStream {
 public:
  // Joins HAL as `component` and attaches to sampler channel `channel`;
  // with `outputs`, also creates the edge's output pins (below) and links
  // them into the machine's signals (a reader only, e.g. a diagnostic, must
  // not: linking an output takes the signal over).
  // Throws std::runtime_error naming the cause and the fix: HAL not
  // running (start LinuxCNC), no sampler (load deploy/linuxcnc/smc-edge.hal),
  // a sampler with other pins (its cfg must be kRecordTypes).
  explicit HalSampleStream(const std::string& component, int channel = 0, bool outputs = false);
  ~HalSampleStream();
  HalSampleStream(const HalSampleStream&) = delete;
  HalSampleStream& operator=(const HalSampleStream&) = delete;

  // Real-time safe. The next record, if the stream has one.
  bool read(HalRecord& out) noexcept;
  // Records waiting in the stream now.
  int backlog() const noexcept;

  // Counted by read(): gaps in the sampler's numbering, and repeats.
  std::uint64_t lost() const noexcept { return lost_; }
  std::uint64_t repeated() const noexcept { return repeated_; }
  std::uint64_t records() const noexcept { return records_; }
  // Records the sampler could not store because the stream was full.
  int overruns() const noexcept;

  // The edge's outputs on the machine: pins <component>.adaptive-feed (the
  // share of the program's F, 0..1) and <component>.feed-inhibit, linked at
  // start to the signals smc-adaptive-feed and smc-feed-inhibit of
  // deploy/linuxcnc/smc-edge.hal (which drive motion.adaptive-feed and
  // motion.feed-inhibit). They start at "program feed, no hold". Real-time
  // safe; no effect without `outputs`.
  void set_adaptive_feed(double share) noexcept;  // clamped to [0, 1]
  void set_feed_inhibit(bool on) noexcept;
  // The edge is alive: toggles <component>.heartbeat at most every 5 ms
  // (the servo thread must see each level). smc-edge.hal's watchdog
  // inhibits the feed when it stops toggling for its timeout, once
  // <component>.joined (set when the outputs are linked) is true. Call it
  // every loop tick with a monotonic time. Real-time safe.
  void heartbeat(std::int64_t now_ns) noexcept;
  // <component>.job-start, linked to smc-job-start when the configuration
  // has it (deploy/linuxcnc/smc-dyno.hal: a fresh blank; on a real machine
  // a part counter): high while a job's program is being started.
  void set_job_start(bool on) noexcept;
  // False when the HAL configuration has no such signals (the pins then
  // act on nothing).
  bool outputs_linked() const noexcept { return linked_; }

 private:
  struct Impl;
  Impl* impl_ = nullptr;
  std::uint64_t lost_ = 0, repeated_ = 0, records_ = 0;
  std::uint32_t last_no_ = 0;
  bool linked_ = false;
  bool beat_ = false;
  std::int64_t last_beat_ns_ = 0;
};

}  // namespace smc::edge::linuxcnc
