// Module E: automatic chatter detector.

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <unsupported/Eigen/FFT>

#include "smc/edge/modules.hpp"
#include "smc/machining/structure.hpp"

namespace smc::edge {

struct AutomaticChatterDetector::Fft {
  Eigen::FFT<double> fft;
};

AutomaticChatterDetector::AutomaticChatterDetector()
    : Module(ModuleId::E), fft_(std::make_unique<Fft>()) {
  fft_->fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
}

AutomaticChatterDetector::~AutomaticChatterDetector() = default;

namespace {

// Appends `text` (or the decimal digits of `n`) at `at` in `out`, leaving
// room for the terminating NUL; nothing is allocated (the real-time path).
template <size_t N>
void append(std::array<char, N>& out, size_t& at, const char* text) noexcept {
  for (; *text != '\0' && at + 1 < N; ++text) out[at++] = *text;
  out[at] = '\0';
}
template <size_t N>
void append(std::array<char, N>& out, size_t& at, int n) noexcept {
  char digits[12];
  int k = 0;
  unsigned v = n < 0 ? 0u : static_cast<unsigned>(n);
  do {
    digits[k++] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0 && k < 11);
  while (k > 0 && at + 1 < N) out[at++] = digits[--k];
  out[at] = '\0';
}

}  // namespace

void AutomaticChatterDetector::channel_mismatch_reason(int brought) noexcept {
  // Short enough for the edge status's 127 characters with its prefix
  // ("module error in module E (...)").
  size_t at = 0;
  const int given = std::max(brought, 1);  // 0: the one sample a period
  append(channel_error_, at, "the drive gives ");
  append(channel_error_, at, given);
  append(channel_error_, at, given == 1 ? " wideband sample" : " wideband samples");
  append(channel_error_, at, " a period; operation.wideband_samples_per_tick is ");
  append(channel_error_, at, per_tick_);
}

void AutomaticChatterDetector::configure(const EdgeParameters& p) {
  p_ = p;
  channel_error_[0] = '\0';
  const auto most = static_cast<size_t>(std::max(p.max_samples_per_revolution, 1));
  buffer_.assign(most, 0.0);
  spectrum_.assign(most / 2 + 1, {});
  // A revolution has as many samples as the measured speed gives it, within
  // the machine's speed range. Plan every FFT size of that range now, the
  // largest last, so that the plans and the scratch buffers exist before the
  // loop starts: later calls of these sizes do not allocate.
  const int fewest = std::clamp(p.min_samples_per_revolution, 1, static_cast<int>(most));
  for (int n = fewest; n <= static_cast<int>(most); ++n) {
    fft_->fft.fwd(spectrum_.data(), buffer_.data(), n);
  }
  // The vibration estimate: each y mode discretised exactly at the wideband
  // channel's sample period (as the simulated mill discretises its own
  // structure; the loop's, or a fraction of it where the channel samples
  // faster); a ring holding this revolution and the one before, at the
  // slowest supervised speed, with room for the fractional delay's taps.
  per_tick_ =
      std::clamp(p.vibration_samples_per_tick, 1, EdgeParameters::kMaxVibrationSamplesPerTick);
  channel_period_s_ = p.sample_period_s / per_tick_;
  mode_count_ = 0;
  for (int i = 0; i < std::min(p.vibration_mode_count, EdgeParameters::kMaxVibrationModes); ++i) {
    const auto& m = p.vibration_modes[i];
    const auto d = machining::discretise(
        machining::Mode{m.natural_frequency_rad_s, m.damping_ratio, m.stiffness_n_per_mm},
        channel_period_s_);
    VibrationMode& v = modes_[static_cast<size_t>(mode_count_++)];
    v = VibrationMode{d.p11, d.p12, d.p21, d.p22, d.g1, d.g2, 0, 0};
  }
  const size_t wide_most = most * static_cast<size_t>(per_tick_);
  vibration_.assign(mode_count_ > 0 ? 2 * wide_most + 2 * FractionalDelay::kMaxHalf + 4 : 0, 0.0);
  vibration_buffer_.assign(mode_count_ > 0 ? wide_most : 0, 0.0);
  vibration_spectrum_.assign(mode_count_ > 0 ? 2 * (wide_most / 2 + 1) : 0, {});
  delay_gain_.assign(mode_count_ > 0 ? wide_most / 2 + 1 : 0, 1.0);
  // At most one order a bin below the Nyquist frequency (the slowest
  // speed's revolution has `wide_most` samples).
  const size_t orders = mode_count_ > 0 ? wide_most / 2 + 1 : 0;
  order_twice_cos_.assign(orders, 0.0);
  order_s1_.assign(orders, 0.0);
  order_s2_.assign(orders, 0.0);
  // The estimate's revolutions at the channel's rate: their plans too,
  // the largest last.
  if (mode_count_ > 0 && per_tick_ > 1) {
    for (int n = fewest; n <= static_cast<int>(most); ++n) {
      fft_->fft.fwd(vibration_spectrum_.data(), vibration_buffer_.data(), n * per_tick_);
    }
  }
  delay_gain_n_ = 0;
  reset();
}

void AutomaticChatterDetector::reset() noexcept {
  filled_ = 0;
  above_ = 0;
  previous_mean_ = 0;
  last_engagement_ = std::numeric_limits<double>::quiet_NaN();
  most_engaged_ = last_engagement_;
  for (auto& m : modes_) m.q = m.w = 0;
  vibration_at_ = vibration_run_ = 0;
  wide_channel_ = false;
  q1_ = q2_ = q3_ = s1_ = s2_ = std::numeric_limits<double>::quiet_NaN();
  q_above_ = flip_above_ = 0;
  whole1_ = false;
  last_flip_ = 0;
}

Status AutomaticChatterDetector::on_sample(Signals& s) noexcept {
  if (filled_ < static_cast<int>(buffer_.size())) {
    buffer_[static_cast<size_t>(filled_++)] = s.sample.f_z_n;
  }
  if (mode_count_ == 0) return Status::kOk;
  const ForceSample& in = s.sample;
  if (!std::isfinite(in.f_y_wide_n)) {
    vibration_run_ = 0;  // a gap: the comparison starts again
    return Status::kOk;
  }
  // The channel's samples of this period: as many as the configuration
  // says it brings (operation.wideband_samples_per_tick), or the drive and
  // E disagree on its rate, and the estimate would be wrong: an error (the
  // core holds the feed).
  if (per_tick_ > 1 ? in.wide_count != per_tick_ : in.wide_count > 1) {
    if (channel_error_[0] == '\0') channel_mismatch_reason(in.wide_count);
    return fail(channel_error_.data());
  }
  const double* f = per_tick_ > 1 ? in.f_y_wide_sub_n : &in.f_y_wide_n;
  for (int j = 0; j < per_tick_; ++j) {
    if (!std::isfinite(f[j])) {
      vibration_run_ = 0;
      return Status::kOk;
    }
    double v = 0;
    for (int i = 0; i < mode_count_; ++i) {
      VibrationMode& m = modes_[static_cast<size_t>(i)];
      const double q = m.p11 * m.q + m.p12 * m.w + m.g1 * f[j];
      m.w = m.p21 * m.q + m.p22 * m.w + m.g2 * f[j];
      m.q = q;
      v += q;
    }
    vibration_[static_cast<size_t>(vibration_at_ % vibration_.size())] = v;
    ++vibration_at_;
    ++vibration_run_;
  }
  wide_channel_ = true;
  return Status::kOk;
}

double AutomaticChatterDetector::vibration_correction(double frequency_hz,
                                                      double* held_norm) const noexcept {
  using C = std::complex<double>;
  const double omega = 2 * std::numbers::pi * frequency_hz;
  const C s(0, omega);
  const C z = std::polar(1.0, omega * channel_period_s_);
  C held = 0, structure = 0;
  for (int i = 0; i < mode_count_; ++i) {
    const VibrationMode& m = modes_[static_cast<size_t>(i)];
    const auto& c = p_.vibration_modes[i];
    const double wn = c.natural_frequency_rad_s;
    structure += wn * wn / c.stiffness_n_per_mm / (s * s + 2 * c.damping_ratio * wn * s + wn * wn);
    // First row of (zI - P)^-1 G: the held force's path to the displacement.
    const C det = (z - m.p11) * (z - m.p22) - m.p12 * m.p21;
    held += ((z - m.p22) * m.g1 + m.p12 * m.g2) / det;
  }
  const double fc = p_.vibration_sensor_cutoff_hz;
  const double r = fc > 0 ? frequency_hz / fc : 0;
  // |Butterworth|^2 of the channel's order: 1 / (1 + r^(2 order)).
  double r_2n = 1;
  for (int i = 0; i < p_.vibration_sensor_order; ++i) r_2n *= r * r;
  const double sensor = 1 / (1 + r_2n);
  const double below = std::norm(held) * sensor;
  if (held_norm != nullptr) *held_norm = std::norm(held);
  return below > 0 ? std::min(std::norm(structure) / below, kMaxCorrection) : kMaxCorrection;
}

double AutomaticChatterDetector::vibration_ratio(int samples, double period_samples) noexcept {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  last_flip_ = 0;
  if (mode_count_ == 0 || samples < 4 || !(period_samples >= 1)) return nan;
  // In the channel's samples (per_tick_ of them a sample period).
  samples *= per_tick_;
  period_samples *= per_tick_;
  if (static_cast<size_t>(samples) > vibration_buffer_.size()) return nan;
  // This revolution and the one before, back to the sample before the first
  // one it interpolates, must lie in the unbroken run and in the ring.
  const auto whole = static_cast<uint64_t>(period_samples);
  const double w = period_samples - static_cast<double>(whole);
  // The revolution before, at the same angle: a band-limited fractional
  // delay (linear interpolation reads a repeating vibration near the tool
  // mode as a change of up to half of it), with no more taps each side
  // than a revolution has samples, so that none reaches past the newest.
  const int half = static_cast<int>(std::min<uint64_t>(FractionalDelay::kMaxHalf, whole));
  if (half < 1) return nan;
  delay_.set(w > 0 ? 1 - w : 0, half);
  const auto reach = static_cast<uint64_t>(samples) + whole + static_cast<uint64_t>(half) + 1;
  if (reach > vibration_run_ || reach > vibration_.size()) return nan;
  const uint64_t size = vibration_.size();
  auto at = [&](uint64_t k) { return vibration_[static_cast<size_t>(k % size)]; };
  const auto n = static_cast<size_t>(samples);
  const size_t bins = n / 2 + 1;
  std::complex<double>* change = vibration_spectrum_.data();
  std::complex<double>* now = change + bins;
  // The change: v at k less v at k - period, (1 - w) past sample k - whole
  // - 1 (or sample k - whole itself).
  const uint64_t first = vibration_at_ - static_cast<uint64_t>(samples);
  const uint64_t back = w > 0 ? whole + 1 : whole;
  for (size_t i = 0; i < n; ++i) {
    const uint64_t k = first + i;
    vibration_buffer_[i] = at(k) - delay_.at(at, k - back);
  }
  fft_->fft.fwd(change, vibration_buffer_.data(), static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) vibration_buffer_[i] = at(first + i);
  fft_->fft.fwd(now, vibration_buffer_.data(), static_cast<Eigen::Index>(n));
  // Both energies by Parseval, each bin corrected from what the estimate
  // passes to what the structure does at that frequency.
  const double df = 1.0 / (static_cast<double>(n) * channel_period_s_);
  const double noise = p_.vibration_sensor_noise_rms_n;
  const double noise_bin = static_cast<double>(n) * noise * noise;
  double changed = 0, energy = 0, noise_changed = 0, noise_energy = 0;
  double dc = 0, noise_dc = 0;
  // The delay's power gain per bin, for the noise through it: kept while
  // the revolution's size and the point between samples hold.
  if (noise > 0 && (delay_gain_n_ != n || delay_gain_u_ != delay_.fraction() ||
                    delay_gain_half_ != delay_.half())) {
    delay_gain_n_ = n;
    delay_gain_u_ = delay_.fraction();
    delay_gain_half_ = delay_.half();
    for (size_t k = 0; k < bins; ++k) {
      delay_gain_[k] = delay_.gain_squared(2 * std::numbers::pi * static_cast<double>(k) * df *
                                           channel_period_s_);
    }
  }
  for (size_t k = 0; k < bins; ++k) {
    const bool single = k == 0 || (n % 2 == 0 && k == n / 2);
    const double f = static_cast<double>(k) * df;
    double held_norm = 0;  // |H_held|^2: the noise's path into the estimate
    const double c = (single ? 1.0 : 2.0) * vibration_correction(f, &held_norm);
    changed += c * std::norm(change[k]);
    energy += c * std::norm(now[k]);
    if (k == 0) dc = c * std::norm(now[k]);
    if (noise > 0) {
      const double delayed = delay_gain_[k];
      noise_energy += c * noise_bin * held_norm;
      noise_changed += c * noise_bin * held_norm * (1 + delayed);
      if (k == 0) noise_dc = c * noise_bin * held_norm;
    }
  }
  changed = std::max(changed - noise_changed, 0.0);
  energy -= noise_energy;
  // The share of the AC energy at the spindle orders halfway between tooth
  // harmonics (a period doubling, with an even number of teeth). Each such
  // order below the Nyquist frequency is read by its own Fourier sum over
  // the revolution's samples, as the label reads the mill's (the label's
  // sums are its own, in runner.cpp: the study compares the two). Where a
  // revolution is not a whole number of samples the FFT's bins are not the
  // spindle orders, and the bins next to them read it at 0.44-1.43 of the
  // mill's own (edge/CHATTER.md, "Period doubling"). Each is corrected as
  // q's bins are, less the channel's expected noise (a Fourier sum of n
  // samples of white noise has the power of a bin).
  const int teeth = std::max(p_.teeth, 0);
  const double ac = energy - (dc - noise_dc);
  last_flip_ = 0;
  if (teeth >= 2 && teeth % 2 == 0 && ac > 0) {
    const double mean = now[0].real() / static_cast<double>(n);
    const double order_hz = 1.0 / (period_samples * channel_period_s_);
    const double nyquist_hz = 0.5 / channel_period_s_;
    // |sum of (v_i - mean) e^(-i omega i)|^2 of every order by Goertzel's
    // recurrence, the orders side by side in the loop over the samples, so
    // that no order waits on its own last step.
    size_t orders = 0;
    for (int order = teeth / 2; order * order_hz < nyquist_hz && orders < order_s1_.size();
         order += teeth, ++orders) {
      order_twice_cos_[orders] =
          2 * std::cos(2 * std::numbers::pi * order * order_hz * channel_period_s_);
      order_s1_[orders] = order_s2_[orders] = 0;
    }
    const double* __restrict twice_cos = order_twice_cos_.data();
    double* __restrict s1 = order_s1_.data();
    double* __restrict s2 = order_s2_.data();
    for (size_t i = 0; i < n; ++i) {
      const double x = vibration_buffer_[i] - mean;
      for (size_t j = 0; j < orders; ++j) {
        const double s0 = x + twice_cos[j] * s1[j] - s2[j];
        s2[j] = s1[j];
        s1[j] = s0;
      }
    }
    double flip = 0;
    for (size_t j = 0; j < orders; ++j) {
      const double f = (teeth / 2 + static_cast<double>(j) * teeth) * order_hz;
      const double power = s1[j] * s1[j] + s2[j] * s2[j] - twice_cos[j] * s1[j] * s2[j];
      double held_norm = 0;
      const double c = 2 * vibration_correction(f, &held_norm);
      flip += c * (power - (noise > 0 ? noise_bin * held_norm : 0.0));
    }
    last_flip_ = std::clamp(flip / ac, 0.0, 1.0);
  }
  return energy > 0 ? std::sqrt(changed / energy) : nan;
}

double AutomaticChatterDetector::statistic(int samples, double spindle_rpm,
                                           double* frequency_hz) noexcept {
  if (frequency_hz != nullptr) *frequency_hz = 0;
  const int fewest = std::max(p_.min_samples_per_revolution, 4);
  if (samples < fewest || samples > static_cast<int>(buffer_.size())) return 0.0;
  const auto n = static_cast<size_t>(samples);
  double mean = 0;
  for (size_t i = 0; i < n; ++i) mean += buffer_[i];
  mean /= static_cast<double>(n);
  last_mean_ = mean;
  double ac_power = 0;
  for (size_t i = 0; i < n; ++i) {
    buffer_[i] -= mean;
    ac_power += buffer_[i] * buffer_[i];
  }
  const double rms = std::sqrt(ac_power / static_cast<double>(n));
  if (rms < p_.chatter_min_rms_n) return 0.0;

  // One revolution's samples: when the speed is not a whole number of
  // samples per revolution the window is the nearest whole count, and the
  // bins lie within half a sample period's share of the spindle harmonics.
  fft_->fft.fwd(spectrum_.data(), buffer_.data(), static_cast<Eigen::Index>(n));
  const double fs = 1.0 / p_.sample_period_s;
  const double df = fs / static_cast<double>(n);
  const double tooth_hz = p_.teeth * spindle_rpm / 60.0;
  // The bin nearest each tooth harmonic, at most: at low speeds the bins
  // are closer than the configured guard.
  const double guard = std::min(p_.harmonic_guard_hz, 0.6 * df);
  double total = 0, chatter = 0, peak = 0;
  for (size_t k = 1; k <= n / 2; ++k) {
    const double e = std::norm(spectrum_[k]);
    total += e;
    const double f = static_cast<double>(k) * df;
    if (f < p_.chatter_band_low_hz || f > p_.chatter_band_high_hz) continue;
    const double nearest = tooth_hz > 0 ? std::round(f / tooth_hz) * tooth_hz : 0;
    if (std::fabs(f - nearest) <= guard) continue;
    chatter += e;
    if (e > peak) {
      peak = e;
      if (frequency_hz != nullptr) *frequency_hz = f;
    }
  }
  return total > 0 ? chatter / total : 0.0;
}

Status AutomaticChatterDetector::update(Signals& s) noexcept {
  const int samples = filled_;
  filled_ = 0;
  s.chatter_vibration_ratio = 0;
  s.chatter_vibration_flip = 0;
  // A partial revolution (the detector was just activated, or a bad sample
  // never reached it): no decision, and the estimate's comparison starts
  // again, since the ring has a gap.
  if (samples != s.revolution_samples) {
    vibration_run_ = 0;
    wide_channel_ = false;
    q1_ = q2_ = q3_ = s1_ = s2_ = std::numeric_limits<double>::quiet_NaN();
    q_above_ = flip_above_ = 0;
    whole1_ = false;
    return Status::kOk;
  }
  double freq = 0;
  const double ratio = statistic(samples, s.spindle_rpm, &freq);
  if (!std::isfinite(ratio)) return fail("the chatter statistic of the revolution is not finite");
  // Entering or leaving the part, or while a controller moves the feed
  // fast, the mean force changes from one revolution to the next and the
  // revolution is not a repetition of the one before: no decision then.
  const double change = std::fabs(last_mean_ - previous_mean_);
  const bool steady = previous_mean_ != 0 && change <= kMaxMeanChange * std::fabs(previous_mean_);
  const double mean_before = previous_mean_;
  previous_mean_ = last_mean_;
  // Nor while the cutter leaves the part (the drive's engagement below the
  // most it reached since it last rose: it moves in steps, and may hold for
  // a revolution; NaN: unknown, judged): the part's end takes part of the
  // arc every revolution, however slowly the mean moves, and with runout
  // that change read as chatter at stable exits of the detector study
  // (edge/CHATTER.md). Entering, it is judged: most chatter starts
  // there, none started while leaving in that study.
  const double engagement = s.engagement;
  // A sudden change of cut that the drive's engagement does not describe (a
  // step in the depth left by an aborted pass, say): the mean force rose by
  // more than a tenth beyond the engagement's own rise (unknown: none).
  const double engaged_more =
      engagement > 0 && last_engagement_ > 0 ? engagement / last_engagement_ : 1.0;
  const bool stepped =
      mean_before != 0 &&
      std::fabs(last_mean_) > std::fabs(mean_before) * engaged_more * (1 + kMaxMeanChange);
  if (!(engagement <= last_engagement_)) most_engaged_ = engagement;  // rose, or was unknown
  // The cutter wholly in the part from the revolution's start to its end
  // (it enters or leaves monotonically; NaN, unknown: not so), and not
  // crossing an aborted pass's ledge (a step in the depth, and the
  // controller's answer to it: an entry of its own).
  const bool whole =
      engagement >= kWholeEngagement && last_engagement_ >= kWholeEngagement && !s.crossing_ledge;
  last_engagement_ = engagement;
  const bool leaving = engagement < most_engaged_ - 1e-9;

  // The vibration estimate, where the sensor gives the wideband F_y. Judged
  // entering the part and while the feed moves (the estimate's change falls
  // as the cutter enters; chatter makes it grow), not while leaving, nor
  // across a step in the cut (the estimate's pattern changes with it).
  // (The channel is there when the revolution had a finite sample of it: a
  // bad sample does not switch the rules, it only breaks the comparison.)
  const bool estimate = mode_count_ > 0 && wide_channel_;
  wide_channel_ = false;
  if (estimate) {
    const double rpm = s.spindle_rpm;
    const double period = std::isfinite(rpm) && rpm >= p_.min_spindle_rpm && rpm > 0
                              ? 60.0 / rpm / p_.sample_period_s
                              : std::numeric_limits<double>::quiet_NaN();
    const double q = vibration_ratio(samples, period);
    if (std::isfinite(q) && !leaving && !stepped) {
      s.chatter_vibration_ratio = q;
      // Above `rise` and rising, then rising again (the onset's own
      // pattern); above `climb` and rising three times in a row (slower
      // growth, from lower, needs one revolution more of it); or high three
      // in a row. A rise is by more than `growth` (q's own error from one
      // revolution to the next is a few per cent). NaN (no judged revolution
      // there) compares false.
      const double g = p_.chatter_vibration_growth;
      const bool rising = q1_ > p_.chatter_vibration_rise && q1_ > g * q2_ && q > g * q1_;
      const bool climbing =
          q2_ > p_.chatter_vibration_climb && q2_ > g * q3_ && q1_ > g * q2_ && q > g * q1_;
      // The onset's pause: above `pause` and rising, held above it for a
      // revolution (chatter locking for a while, or q alternating as it
      // grows), then past where it rose to.
      const double hold = p_.chatter_vibration_pause;
      const bool pausing = q2_ > hold && q2_ > g * q3_ && q1_ > hold && q > g * q2_;
      // Uneven growth: above `net` three revolutions in a row, grown by
      // half (`net_growth`) over the revolution before them and past the
      // first of them, never falling by more than `net_dip` on the way (q
      // alternating as it grows, or the estimate's error of a few per
      // cent breaking a rise).
      const double floor = p_.chatter_vibration_net, keep = 1 - p_.chatter_vibration_net_dip;
      const bool net = q3_ > 0 && q2_ > floor && q1_ > floor && q > floor &&
                       q > p_.chatter_vibration_net_growth * q3_ && q > q2_ && q1_ >= keep * q2_ &&
                       q >= keep * q1_;
      // A jump: past `jump`, by `jump_growth` over the revolution before,
      // and held above it the next revolution within `jump_dip` of the
      // jump. Chatter drawn onto a spindle order grows for a revolution or
      // two and then repeats itself, so that q falls back while the
      // vibration keeps its size (the paper's cut on the simulated mill at
      // 1509 rpm: 0.124, 0.273, 0.269, then 0.117); a stable cut's q never
      // jumps by a fifth to above it and holds (edge/CHATTER.md, "The
      // rules' margins").
      const double jump = p_.chatter_vibration_jump;
      const bool jumped = q1_ > jump && q1_ > p_.chatter_vibration_jump_growth * q2_ && q > jump &&
                          q >= (1 - p_.chatter_vibration_jump_dip) * q1_;
      // A steep climb: three rises in a row, each by more than
      // `steep_growth`, from at least `steep_from` to past `steep`. Chatter
      // that starts from low grows fast (LinuxCNC's job-shop cut: 0.069,
      // 0.119, 0.204, 0.237, then 0.140) and may fall back before the rise
      // rule's second rise above `rise`; a stable cut's q climbs that
      // steeply only to below it (edge/CHATTER.md, "The rules' margins").
      // Below `steep_from` q is a repeating cut's own, whose rises mean
      // nothing (rounding, where the cut repeats itself exactly).
      const double sg = p_.chatter_vibration_steep_growth;
      const bool climbed =
          q3_ > p_.chatter_vibration_steep_from && q > sg * q1_ && q1_ > sg * q2_ && q2_ > sg * q3_;
      const bool steep = climbed && q > p_.chatter_vibration_steep;
      // The same climb to past `confirmed` only, where F_z's non-harmonic
      // share S (judged on its own channel) rose by more than
      // `confirmed_growth` in each of the last two revolutions: the two
      // channels' evidence together. A stable cut's q climbs steeply while
      // S rises so only to far below it (edge/CHATTER.md, "The rules'
      // margins"); chatter on LinuxCNC is caught a revolution earlier.
      const double sq = steady && !leaving ? ratio : std::numeric_limits<double>::quiet_NaN();
      const double cg = p_.chatter_vibration_confirmed_growth;
      const bool confirmed = climbed && q > p_.chatter_vibration_confirmed && s2_ > 0 &&
                             s1_ > cg * s2_ && sq > cg * s1_;
      q_above_ = q > p_.chatter_vibration_level ? q_above_ + 1 : 0;
      // Held: above `held` on average over this revolution and the one
      // before, neither below `held_floor` (one revolution's jump is no
      // hold), both with the cutter wholly in the part. There a stable
      // cut's q stays far below the label's 0.15 (at most 0.11 over two
      // revolutions in the detector study's sets at 10 kHz), while chatter
      // at the edge of stability may hover just above it for revolutions
      // before it grows (0.154, 0.151, 0.160, 0.167 at 900 rpm), which no
      // rule on its growth reads. Entering the part, or crossing a ledge,
      // stable cuts' q passes 0.15 for revolutions: no level rule there
      // (edge/CHATTER.md, "The held rule").
      const double floor_held = p_.chatter_vibration_held_floor;
      const bool held = whole && whole1_ && q > floor_held && q1_ > floor_held &&
                        (q + q1_) / 2 > p_.chatter_vibration_held;
      // A period doubling: with an even number of teeth the vibration at
      // the spindle orders halfway between tooth harmonics repeats every
      // revolution, so q sees it only while it grows (from the first
      // hundredths of a per cent of a stable cut's energy to 0.9 and more of
      // it in the study's full-width cuts, q at 0.02-0.10 meanwhile). Its
      // share above `flip` in `flip_revolutions` judged revolutions in a
      // row (3 with the shipped 10 kHz channel, as the label's onset asks;
      // 2 with a channel at the loop's rate).
      s.chatter_vibration_flip = last_flip_;
      flip_above_ = last_flip_ > p_.chatter_vibration_flip ? flip_above_ + 1 : 0;
      if (rising || climbing || pausing || net || jumped || steep || confirmed || held ||
          q_above_ >= kVibrationConfirm ||
          flip_above_ >= std::max(1, p_.chatter_vibration_flip_revolutions)) {
        s.chatter_detected = true;
      }
      q3_ = q2_;
      q2_ = q1_;
      q1_ = q;
      whole1_ = whole;
      s2_ = s1_;
      s1_ = sq;
    } else if (!(stepped && !leaving && std::isfinite(q) &&
                 p_.chatter_vibration_keep_across_steps && !s.crossing_ledge)) {
      q1_ = q2_ = q3_ = s1_ = s2_ = std::numeric_limits<double>::quiet_NaN();
      q_above_ = flip_above_ = 0;
      whole1_ = false;
    }
    // (Across a step, with keep_across_steps, the revolution is not judged
    // and the rules' history is kept: chatter's own growth raises the mean
    // F_z so, and forgetting the revolutions before it made E a revolution
    // or two late on fast-growing chatter. Not where the cutter crosses an
    // aborted pass's ledge: that step is the cut's, and the controller's
    // answer to it changes the vibration from one revolution to the next
    // as chatter would.)
  }

  if (!steady || leaving) {
    s.chatter_ratio = 0;  // not judged
    // With the estimate, S's confirmation restarts (as the study measured
    // it); alone, it neither counts towards nor breaks one.
    if (estimate) above_ = 0;
    return Status::kOk;
  }
  s.chatter_ratio = ratio;
  s.chatter_frequency_hz = freq;
  // With the estimate, S is at most a backup (off as shipped:
  // Parameters::chatter_vibration_backup); without it, E's statistic.
  const double threshold = estimate ? p_.chatter_vibration_backup : p_.chatter_threshold;
  const int confirm = estimate ? kVibrationConfirm : p_.chatter_confirm_revolutions;
  above_ = ratio > threshold ? above_ + 1 : 0;
  if (above_ >= confirm) s.chatter_detected = true;
  return Status::kOk;
}

}  // namespace smc::edge
