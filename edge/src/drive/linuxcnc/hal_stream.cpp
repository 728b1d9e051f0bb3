#include "hal_stream.hpp"

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
};

HalSampleStream::HalSampleStream(const std::string& component, int channel) : impl_(new Impl) {
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
        "): load it in the servo thread as deploy/linuxcnc/smc-edge.hal does (loadrt sampler "
        "cfg=" +
        kRecordTypes + ")");
  }
  impl_->attached = true;
  hal_ready(impl_->comp);
}

HalSampleStream::~HalSampleStream() {
  if (impl_ == nullptr) return;
  if (impl_->attached) hal_stream_detach(&impl_->stream);
  if (impl_->comp >= 0) hal_exit(impl_->comp);
  delete impl_;
}

bool HalSampleStream::read(HalRecord& out) noexcept {
  if (!hal_stream_readable(&impl_->stream)) return false;
  hal_stream_data d[10];
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
