#include "hal_stream.hpp"

#include <ctime>
#include <stdexcept>

// hal.h is C and warns under C++20 -Werror: included as a system header
// (CMake: -isystem), compiled as userspace (-DULAPI).
extern "C" {
#include <hal.h>
}

namespace smc::edge::linuxcnc {

struct HalSampleStream::Impl {
  int comp = -1;
  hal_stream_t stream{};
  bool attached = false;
  struct Pins {
    hal_float_t* adaptive_feed;
    hal_bit_t* feed_inhibit;
    hal_bit_t* joined;
    hal_bit_t* heartbeat;
    hal_bit_t* job_start;
  };
  Pins* pins = nullptr;  // in HAL shared memory (hal_malloc)
};

HalSampleStream::HalSampleStream(const std::string& component, int channel, bool outputs)
    : impl_(new Impl) {
  impl_->comp = hal_init(component.c_str());
  if (impl_->comp < 0) {
    const int err = -impl_->comp;
    delete impl_;
    impl_ = nullptr;
    throw std::runtime_error(
        "cannot join HAL as '" + component + "' (error " + std::to_string(err) +
        "): is LinuxCNC running, as this user? Start it with deploy/linuxcnc/run.sh start");
  }
  const int r = hal_stream_attach(&impl_->stream, impl_->comp, kSamplerKey + channel, kRecordTypes);
  if (r < 0) {
    hal_exit(impl_->comp);
    delete impl_;
    impl_ = nullptr;
    throw std::runtime_error(
        "no sampler stream " + std::to_string(channel) + " with pins '" + kRecordTypes +
        "' (error " + std::to_string(-r) +
        "): is LinuxCNC running, with deploy/linuxcnc/smc-edge.hal loaded (loadrt sampler cfg=" +
        kRecordTypes +
        " in the servo thread)? Start the headless mill with deploy/linuxcnc/run.sh start");
  }
  impl_->attached = true;
  if (!outputs) {
    hal_ready(impl_->comp);
    return;
  }
  impl_->pins = static_cast<Impl::Pins*>(hal_malloc(sizeof(Impl::Pins)));
  if (impl_->pins == nullptr ||
      hal_pin_float_newf(HAL_OUT, &impl_->pins->adaptive_feed, impl_->comp, "%s.adaptive-feed",
                         component.c_str()) != 0 ||
      hal_pin_bit_newf(HAL_OUT, &impl_->pins->feed_inhibit, impl_->comp, "%s.feed-inhibit",
                       component.c_str()) != 0 ||
      hal_pin_bit_newf(HAL_OUT, &impl_->pins->joined, impl_->comp, "%s.joined",
                       component.c_str()) != 0 ||
      hal_pin_bit_newf(HAL_OUT, &impl_->pins->heartbeat, impl_->comp, "%s.heartbeat",
                       component.c_str()) != 0 ||
      hal_pin_bit_newf(HAL_OUT, &impl_->pins->job_start, impl_->comp, "%s.job-start",
                       component.c_str()) != 0) {
    hal_stream_detach(&impl_->stream);
    hal_exit(impl_->comp);
    delete impl_;
    impl_ = nullptr;
    throw std::runtime_error("cannot create the HAL pins of '" + component +
                             "' (is another component of that name running?)");
  }
  // Program feed, no hold: what the signals hold before any edge joins
  // (linking an output pin gives the signal the pin's value).
  *impl_->pins->adaptive_feed = 1.0;
  *impl_->pins->feed_inhibit = false;
  *impl_->pins->joined = false;
  *impl_->pins->heartbeat = false;
  *impl_->pins->job_start = false;
  hal_ready(impl_->comp);
  // Into the machine's signals, when its HAL configuration has them.
  linked_ = hal_link((component + ".adaptive-feed").c_str(), "smc-adaptive-feed") == 0 &&
            hal_link((component + ".feed-inhibit").c_str(), "smc-feed-inhibit") == 0;
  // The watchdog: joined falls (linking gives the signal the pin's false)
  // and rises, which re-arms a watchdog latched by an edge that died.
  if (linked_ && hal_link((component + ".heartbeat").c_str(), "smc-heartbeat") == 0 &&
      hal_link((component + ".joined").c_str(), "smc-edge-joined") == 0) {
    timespec pause{0, 5'000'000};  // let the servo thread see joined low
    nanosleep(&pause, nullptr);
    *impl_->pins->joined = true;
  }
  // A part counter, or the virtual dynamometer's new blank, when present.
  (void)hal_link((component + ".job-start").c_str(), "smc-job-start");
}

void HalSampleStream::set_job_start(bool on) noexcept {
  if (impl_->pins != nullptr) *impl_->pins->job_start = on;
}

void HalSampleStream::heartbeat(std::int64_t now_ns) noexcept {
  if (impl_->pins == nullptr || now_ns - last_beat_ns_ < 5'000'000) return;
  last_beat_ns_ = now_ns;
  beat_ = !beat_;
  *impl_->pins->heartbeat = beat_;
}

void HalSampleStream::set_adaptive_feed(double share) noexcept {
  if (impl_->pins == nullptr) return;
  if (!(share >= 0)) share = 0;  // NaN too: no feed
  *impl_->pins->adaptive_feed = share > 1 ? 1.0 : share;
}

void HalSampleStream::set_feed_inhibit(bool on) noexcept {
  if (impl_->pins != nullptr) *impl_->pins->feed_inhibit = on;
}

HalSampleStream::~HalSampleStream() {
  if (impl_ == nullptr) return;
  if (impl_->attached) hal_stream_detach(&impl_->stream);
  if (impl_->comp >= 0) hal_exit(impl_->comp);
  delete impl_;
}

bool HalSampleStream::read(HalRecord& out) noexcept {
  if (!hal_stream_readable(&impl_->stream)) return false;
  hal_stream_data d[19];
  unsigned no = 0;
  if (hal_stream_read(&impl_->stream, d, &no) < 0) return false;
  out.fx_n = d[0].f;
  out.fy_n = d[1].f;
  out.fz_n = d[2].f;
  out.spindle_rps = d[3].f;
  out.spindle_revs = d[4].f;
  out.x_mm = d[5].f;
  out.y_mm = d[6].f;
  out.z_mm = d[7].f;
  out.velocity_mm_s = d[8].f;
  out.program_line = d[9].s;
  out.fy_wide_n = d[10].f;
  out.fy_wide_present = d[11].b;
  out.vibration_y_mm = d[12].f;
  out.vibration_present = d[13].b;
  for (int i = 0; i < 4; ++i) out.fy_wide_sub_n[i] = d[14 + i].f;
  out.fy_wide_samples = d[18].s;
  out.sample_no = no;
  if (records_ > 0) {
    if (no == last_no_) {
      ++repeated_;
    } else if (no != last_no_ + 1) {
      lost_ += static_cast<std::uint32_t>(no - last_no_ - 1);
    }
  }
  last_no_ = no;
  ++records_;
  return true;
}

int HalSampleStream::backlog() const noexcept { return hal_stream_depth(&impl_->stream); }

int HalSampleStream::overruns() const noexcept { return hal_stream_num_overruns(&impl_->stream); }

}  // namespace smc::edge::linuxcnc
