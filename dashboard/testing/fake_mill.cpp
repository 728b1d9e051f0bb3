// TEST TOOL: see fake_mill.hpp.
#include "fake_mill.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "smc/grafcet/engine.hpp"
#include "smc/grafcet/model.hpp"
#include "smc/grafcet/parser.hpp"
#include "smc/transport/document.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/names.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::dashboard::testing {

namespace {

namespace tr = smc::transport;
using wire::set_string;

constexpr double kRevolution_s = 0.040;    // 1500 rpm
constexpr int kSamplesPerRevolution = 80;  // 0.5 ms sampling
constexpr double kTeeth = 4;
constexpr double kRpm = 1500;
constexpr double kForceReference_n = 190;  // 745.7 W / 3.93 m/s
constexpr double kCuttingSpeed_m_s = 2 * std::numbers::pi * 0.025 * kRpm / 60;
constexpr double kApproach_mm = 6;
constexpr double kRapid_mm_s = 20;
constexpr double kEntry_mm = 5;  // immersion ramp as the cutter enters the part
constexpr double kRetract_s = 0.8;
constexpr double kIdle_s = 1.5;
constexpr double kSuppressionHold_s = 0.2;
constexpr double kChatterHz = 612;
constexpr double kChatterDetect_n = 40;

// The paper's static feed-force law, F_Y = 0.76 kN d^0.65 f^0.63.
double uncontrolled_force(double depth_mm, double fpt_mm) {
  return 760.0 * std::pow(depth_mm, 0.65) * std::pow(fpt_mm, 0.63);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::uint64_t monotonic_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

std::int64_t unix_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

tr::Schema schema_of(const google::protobuf::Message& m) {
  return tr::Schema{m.GetDescriptor()->full_name(), config::SCHEMA_VERSION_CURRENT};
}

enum class Phase { kIdle, kApproach, kCut, kRetract };

struct JobInfo {
  std::string id;
  std::string part;
  config::SmcVariant variant = config::SMC_II;
  std::string explanation;
  std::vector<double> planned;  // pass depths
  config::JobState state = config::JOB_PLANNED;
  std::uint32_t chatter_events = 0;
  std::uint32_t rewrites = 0;
  double peak_force = 0;
  double start_s = 0;
  double end_s = 0;
  double feed_hold_s = 0;
};

// Everything the fake publishes, shared by all mills (keyed writers).
struct Wire {
  explicit Wire(const FakeCellOptions& o)
      : participant(tr::ParticipantOptions{o.domain_id, {}, o.partition}),
        summary_topic(participant),
        batch_topic(participant),
        situation_topic(participant),
        status_topic(participant),
        chatter_topic(participant),
        progress_topic(participant),
        command_topic(participant),
        config_topic(participant, wire::kConfigTopic),
        program_topic(participant, wire::kProgramTopic),
        job_topic(participant, wire::kJobStatusTopic),
        summaries(summary_topic),
        batches(batch_topic),
        situations(situation_topic),
        statuses(status_topic),
        chatters(chatter_topic),
        progresses(progress_topic),
        commands(command_topic),
        configs(config_topic, schema_of(config::SupervisorConfig::default_instance())),
        programs(program_topic, schema_of(config::PartProgram::default_instance())),
        jobs(job_topic, schema_of(config::JobStatus::default_instance())) {}

  tr::Participant participant;
  tr::Topic<smc_data_ForceSummary> summary_topic;
  tr::Topic<smc_data_ForceBatch> batch_topic;
  tr::Topic<smc_data_SupervisorSituation> situation_topic;
  tr::Topic<smc_data_EdgeStatus> status_topic;
  tr::Topic<smc_data_ChatterEvent> chatter_topic;
  tr::Topic<smc_data_JobProgress> progress_topic;
  tr::Topic<smc_data_OperatorCommand> command_topic;
  tr::Topic<smc_data_Envelope> config_topic;
  tr::Topic<smc_data_Envelope> program_topic;
  tr::Topic<smc_data_Envelope> job_topic;
  tr::Writer<smc_data_ForceSummary> summaries;
  tr::Writer<smc_data_ForceBatch> batches;
  tr::Writer<smc_data_SupervisorSituation> situations;
  tr::Writer<smc_data_EdgeStatus> statuses;
  tr::Writer<smc_data_ChatterEvent> chatters;
  tr::Writer<smc_data_JobProgress> progresses;
  tr::Reader<smc_data_OperatorCommand> commands;
  tr::DocumentWriter configs;
  tr::DocumentWriter programs;
  tr::DocumentWriter jobs;
};

class FakeMill {
 public:
  FakeMill(std::string id, int number, config::SmcVariant variant, const std::string& grafcet_text,
           const FakeCellOptions& options, Wire& w)
      : id_(std::move(id)),
        variant_(variant),
        grafcet_text_(grafcet_text),
        options_(options),
        wire_(w),
        engine_(parse_or_throw(grafcet_text)),
        rng_(options.seed * 7919U + static_cast<std::uint64_t>(number)),
        noise_(0.0, 2.0),
        idle_left_s_(0.4 + 1.1 * (number - 1)) {
    a_ = engine_.input_index("a");
    b_ = engine_.input_index("b");
    c_ = engine_.input_index("c");
    d_ = engine_.input_index("d");
    e_ = engine_.input_index("e");
    for (std::size_t i = 0; i < engine_.num_actions(); ++i) {
      const auto name = engine_.action_name(i);
      action_bit_[i] = (name.size() == 1 && name[0] >= 'A' && name[0] <= 'L') ? name[0] - 'A' : -1;
    }
    job_counter_ = 1000 * number;
    for (int k = 0; k < 3; ++k) queue_.push_back(new_job());
    evaluate();  // the initial situation: 1 -> 2
    publish_situation();
    publish_status();
    for (const auto& j : queue_) publish_job(j);
  }

  const std::string& id() const { return id_; }

  void command(smc_data_OperatorAction action) {
    switch (action) {
      case smc_data_OP_FEED_HOLD_ON:
        feed_hold_ = true;
        break;
      case smc_data_OP_FEED_HOLD_OFF:
        feed_hold_ = false;
        break;
      case smc_data_OP_CHATTER_SIGNAL:
        pulse_c_ = true;
        chatter_source_ = smc_data_CHATTER_OPERATOR;
        break;
    }
  }

  // One spindle revolution.
  void tick(double now_s) {
    now_s_ = now_s;
    ++revolution_;
    const bool held = module(2) || module(6);  // C (feed hold) or G (suppression routine)
    if (held && job_) job_->feed_hold_s += module(2) ? kRevolution_s : 0.0;
    double force = std::abs(noise_(rng_)) + 3.0;  // air: sensor noise
    double feed_mm_s = 0;
    switch (phase_) {
      case Phase::kIdle:
        idle_left_s_ -= kRevolution_s;
        if (idle_left_s_ <= 0 && !held) start_job();
        break;
      case Phase::kApproach:
        if (!held) {
          feed_mm_s = kRapid_mm_s;
          x_mm_ += kRapid_mm_s * kRevolution_s;
        }
        if (x_mm_ >= 0) phase_ = Phase::kCut;
        break;
      case Phase::kCut: {
        const double depth = passes_[pass_index_];
        if (!held) {
          feed_mm_s = fpt_ * kTeeth * kRpm / 60;
          x_mm_ += feed_mm_s * kRevolution_s;
          const double immersion = std::clamp(x_mm_ / kEntry_mm, 0.15, 1.0);
          force = immersion * uncontrolled_force(depth, fpt_) + noise_(rng_);
          in_cut_s_ += kRevolution_s;
          grow_chatter(depth);
          force += chatter_amp_;
          control(force);
        } else {
          force = 8 + std::abs(noise_(rng_));  // dwelling: the tool rubs, no chip
        }
        if (x_mm_ >= options_.part_length_mm) end_pass();
        break;
      }
      case Phase::kRetract:
        retract_left_s_ -= kRevolution_s;
        if (!held) feed_mm_s = kRapid_mm_s;
        if (retract_left_s_ <= 0) {
          phase_ = Phase::kApproach;
          x_mm_ = -kApproach_mm;
        }
        break;
    }
    if (module(6)) suppress();  // G: chatter suppression routine (runs F)

    // Modules I (force processor) and J (contact monitor), when active.
    if (module(8)) f_y_ = force;
    if (module(9)) contact_ = f_y_ > 50;
    // E (automatic chatter detector), when active.
    if (module(4)) {
      confirm_ = chatter_amp_ > kChatterDetect_n ? confirm_ + 1 : 0;
      if (confirm_ >= 2 && !pulse_d_sent_) {
        pulse_d_ = true;
        pulse_d_sent_ = true;
        chatter_source_ = smc_data_CHATTER_AUTOMATIC;
      }
    }
    chatter_flag_ = module(4) && confirm_ >= 2;
    if (job_) job_->peak_force = std::max(job_->peak_force, force);

    evaluate();
    publish_summary(force, feed_mm_s);
    publish_batch(force);
    if (situation_dirty_) publish_situation();
    if (revolution_ % 5 == 0) publish_progress();
    if (revolution_ % 25 == 0 && job_) publish_job(*job_);
    publish_status();
  }

 private:
  static grafcet::Grafcet parse_or_throw(const std::string& text) {
    auto r = grafcet::parse(text, "fake-mill grafcet");
    if (!r.ok()) throw std::runtime_error(r.errors.front().str());
    return std::move(*r.grafcet);
  }

  bool module(int bit) const { return ((modules_ >> bit) & 1U) != 0; }

  JobInfo new_job() {
    JobInfo j;
    j.id = "job-" + std::to_string(++job_counter_);
    j.variant = variant_;
    if (variant_ == config::SMC_II) {
      j.part = "housing-" + std::to_string(job_counter_ % 97);
      j.planned = {2.0};
      j.explanation =
          "No force-process model and no structural model for part " + j.part +
          " (6061-T6, face mill FM25-4T): job-shop part, so SMC II - automatic and operator "
          "chatter detection with suppression (one more pass, equal depths), adaptive force "
          "control (K) to F_ref = 190 N from the 745.7 W spindle limit.";
    } else {
      j.part = "paper-block";
      j.planned = {1.0, 1.0};
      j.explanation =
          "Validated force-process model (F_Y = 0.76 d^0.65 f^0.63 kN, fitted, R^2 0.97) and "
          "structural model found for paper-block: transfer-line part, so SMC I. Time-domain "
          "simulation: one 2 mm pass chatters, 1 mm passes are stable -> 2 passes of 1 mm; "
          "model-based force control (L) to F_ref = 190 N.";
    }
    return j;
  }

  void start_job() {
    job_ = queue_.front();
    queue_.pop_front();
    queue_.push_back(new_job());
    publish_job(queue_.back());
    job_->state = config::JOB_RUNNING;
    job_->start_s = now_s_;
    passes_ = job_->planned;
    pass_index_ = 0;
    revision_ = 1;
    phase_ = Phase::kApproach;
    x_mm_ = -kApproach_mm;
    fpt_ = 0.1;
    chattered_ = false;
    pulse_d_sent_ = false;
    config_id_ = id_ + "/" + job_->id;
    publish_config();
    publish_program();
    publish_job(*job_);
  }

  void end_pass() {
    ++pass_index_;
    in_cut_s_ = 0;
    chatter_amp_ = 0;
    if (pass_index_ < passes_.size()) {
      phase_ = Phase::kRetract;
      retract_left_s_ = kRetract_s;
      return;
    }
    job_->state = config::JOB_DONE;
    job_->end_s = now_s_;
    publish_progress();
    publish_job(*job_);
    job_.reset();
    phase_ = Phase::kIdle;
    idle_left_s_ = kIdle_s;
    passes_.clear();
    pass_index_ = 0;
  }

  // The first 2 mm pass of an SMC II job chatters about 1 s into the cut.
  void grow_chatter(double depth) {
    if (variant_ != config::SMC_II || chattered_ || depth < 1.5 || in_cut_s_ < 1.0) return;
    chatter_amp_ = std::min(220.0, std::max(chatter_amp_, 4.0) * std::exp(kRevolution_s / 0.1));
  }

  // K or L: regulate F_Y to F_ref by the feed per tooth.
  void control(double force) {
    if (!(module(10) || module(11)) || x_mm_ < 0.5) return;
    const double gain = module(11) ? 0.55 : 0.3;
    fpt_ *= std::pow(kForceReference_n / std::max(force, 20.0), gain);
    fpt_ = std::clamp(fpt_, 0.005, 0.3);
  }

  // G, first revolution: F rewrites the program (one more pass, equal
  // depths of what is left); after the 200 ms hold, e = routine complete.
  void suppress() {
    if (suppression_s_ == 0) {
      if (!passes_.empty() && job_) {
        double left = 0;
        for (std::size_t i = pass_index_; i < passes_.size(); ++i) left += passes_[i];
        const std::size_t n = passes_.size() - pass_index_ + 1;
        passes_.resize(pass_index_);
        for (std::size_t i = 0; i < n; ++i) passes_.push_back(left / static_cast<double>(n));
        ++revision_;
        ++job_->chatter_events;
        ++job_->rewrites;
        publish_chatter();
        publish_program();
      }
      chattered_ = true;
      chatter_amp_ = 0;
      confirm_ = 0;
    }
    suppression_s_ += kRevolution_s;
    if (suppression_s_ >= kSuppressionHold_s) {
      pulse_e_ = true;
      suppression_s_ = 0;
      if (phase_ == Phase::kCut) {  // back out and cut the pass again at the new depth
        phase_ = Phase::kRetract;
        retract_left_s_ = kRetract_s;
        in_cut_s_ = 0;
      }
    }
  }

  void evaluate() {
    std::uint64_t in = 0;
    auto set = [&](int idx, bool v) {
      if (idx >= 0 && v) in |= std::uint64_t{1} << idx;
    };
    set(a_, feed_hold_);
    set(b_, contact_);
    set(c_, pulse_c_);
    set(d_, pulse_d_);
    set(e_, pulse_e_);
    inputs_ = static_cast<std::uint32_t>((feed_hold_ ? 1U : 0U) | (contact_ ? 2U : 0U) |
                                         (pulse_c_ ? 4U : 0U) | (pulse_d_ ? 8U : 0U) |
                                         (pulse_e_ ? 16U : 0U));
    pulse_c_ = pulse_d_ = pulse_e_ = false;
    const auto& r = engine_.evaluate(in);
    std::uint32_t modules = 0;
    for (std::size_t i = 0; i < engine_.num_actions(); ++i) {
      if (((r.level_actions >> i) & 1U) && action_bit_[i] >= 0) {
        modules |= 1U << action_bit_[i];
      }
    }
    if (modules & (1U << 6)) modules |= 1U << 5;  // G runs F (the suppressor)
    if (r.active_steps != steps_ || modules != modules_) situation_dirty_ = true;
    steps_ = r.active_steps;
    modules_ = modules;
  }

  double fraction_done() const {
    if (!job_ || passes_.empty()) return 0;
    const double in_pass =
        phase_ == Phase::kCut ? std::clamp(x_mm_ / options_.part_length_mm, 0.0, 1.0) : 0.0;
    return std::clamp(
        (static_cast<double>(pass_index_) + in_pass) / static_cast<double>(passes_.size()), 0.0,
        1.0);
  }

  double depth_removed() const {
    double d = 0;
    for (std::size_t i = 0; i < pass_index_ && i < passes_.size(); ++i) d += passes_[i];
    return d;
  }

  // ---- publishing ------------------------------------------------------------

  void publish_summary(double force, double feed_mm_s) {
    smc_data_ForceSummary s{};
    set_string(s.machine_id, id_);
    s.machine_time_ns = monotonic_ns();
    s.revolution = revolution_;
    s.pass_index = static_cast<std::uint16_t>(pass_index_);
    s.pass_count = static_cast<std::uint16_t>(passes_.size());
    s.f_y_peak_n = static_cast<float>(f_y_);
    s.f_ref_n = job_ ? static_cast<float>(kForceReference_n) : 0.0f;
    s.feedrate_mm_s = static_cast<float>(feed_mm_s);
    s.feed_per_tooth_mm = static_cast<float>(phase_ == Phase::kCut ? fpt_ : 0.0);
    s.depth_mm = static_cast<float>(
        passes_.empty() || pass_index_ >= passes_.size() ? 0.0 : passes_[pass_index_]);
    s.spindle_rpm = static_cast<float>(kRpm);
    s.spindle_power_w = static_cast<float>(force * kCuttingSpeed_m_s);
    s.in_contact = contact_;
    s.chatter = chatter_flag_;
    wire_.summaries.write(s);
  }

  void publish_batch(double force) {
    smc_data_ForceBatch b{};
    set_string(b.machine_id, id_);
    b.sample_period_ns = 500000;
    b.first_sample_time_ns = monotonic_ns() - 40000000ULL;
    b.decimation = 1;
    b.count = kSamplesPerRevolution;
    const double base = std::max(force - chatter_amp_, 0.0);
    for (int i = 0; i < kSamplesPerRevolution; ++i) {
      const double t = i * 0.0005;
      const double tooth = 2 * std::numbers::pi * (kTeeth * kRpm / 60) * t;
      const double chat =
          chatter_amp_ * std::sin(2 * std::numbers::pi * kChatterHz * t + phase_noise_);
      const auto k = static_cast<std::size_t>(i);
      b.f_y_n[k] =
          static_cast<float>(-base * (0.55 + 0.45 * std::cos(tooth)) - chat + noise_(rng_));
      b.f_z_n[k] = static_cast<float>(0.4 * base * (0.6 + 0.4 * std::sin(tooth + 0.7)) +
                                      0.6 * chat + noise_(rng_));
    }
    phase_noise_ += 1.3;
    wire_.batches.write(b);
  }

  void publish_situation() {
    smc_data_SupervisorSituation s{};
    set_string(s.machine_id, id_);
    s.machine_time_ns = monotonic_ns();
    s.sequence_number = ++situation_seq_;
    s.active_steps = steps_;
    s.modules_active = modules_;
    s.inputs = inputs_;
    set_string(s.config_id, config_id_);
    wire_.situations.write(s);
    situation_dirty_ = false;
  }

  void publish_status() {
    smc_data_EdgeState state = smc_data_EDGE_IDLE;
    if (module(2)) {
      state = smc_data_EDGE_FEED_HOLD;
    } else if (job_) {
      state = smc_data_EDGE_RUNNING;
    } else if (!config_id_.empty()) {
      state = smc_data_EDGE_CONFIGURED;
    }
    if (state == last_state_ && revolution_ % 50 != 0) return;
    last_state_ = state;
    smc_data_EdgeStatus s{};
    set_string(s.machine_id, id_);
    s.machine_time_ns = monotonic_ns();
    s.state = state;
    set_string(s.config_id, config_id_);
    set_string(s.job_id, job_ ? job_->id : std::string());
    s.loop_latency_p99_us = 42;
    set_string(s.message, state == smc_data_EDGE_FEED_HOLD ? "operator feed hold"
                          : job_                           ? "cutting"
                                                           : "waiting for a job");
    wire_.statuses.write(s);
  }

  void publish_progress() {
    if (!job_) return;
    smc_data_JobProgress p{};
    set_string(p.machine_id, id_);
    set_string(p.job_id, job_->id);
    p.machine_time_ns = monotonic_ns();
    p.sequence_number = ++progress_seq_;
    p.phase = job_->state == config::JOB_DONE ? smc_data_JOB_DONE : smc_data_JOB_RUNNING;
    p.pass_index = static_cast<std::uint16_t>(std::min(pass_index_, passes_.size() - 1));
    p.pass_count = static_cast<std::uint16_t>(passes_.size());
    p.depth_removed_mm = static_cast<float>(depth_removed());
    p.fraction_done = static_cast<float>(job_->state == config::JOB_DONE ? 1.0 : fraction_done());
    p.chatter_events = job_->chatter_events;
    p.peak_force_n = static_cast<float>(job_->peak_force);
    set_string(p.message,
               "pass " + std::to_string(p.pass_index + 1) + " of " + std::to_string(p.pass_count));
    wire_.progresses.write(p);
  }

  void publish_chatter() {
    smc_data_ChatterEvent e{};
    set_string(e.machine_id, id_);
    e.event_id = ++chatter_event_id_;
    e.machine_time_ns = monotonic_ns();
    e.source = chatter_source_;
    e.frequency_hz =
        chatter_source_ == smc_data_CHATTER_AUTOMATIC ? static_cast<float>(kChatterHz) : 0.0f;
    e.energy_ratio =
        static_cast<float>(std::max(chatter_amp_, kChatterDetect_n) / kChatterDetect_n);
    e.pass_index = static_cast<std::uint16_t>(pass_index_);
    e.new_pass_count = static_cast<std::uint16_t>(passes_.size());
    set_string(e.job_id, job_ ? job_->id : std::string());
    wire_.chatters.write(e);
    chatter_source_ = smc_data_CHATTER_AUTOMATIC;
  }

  config::PartProgram program() const {
    config::PartProgram p;
    p.set_part_id(job_ ? job_->part : std::string());
    double total = 0;
    for (const double d : passes_) {
      auto* pass = p.add_passes();
      pass->set_depth_mm(d);
      pass->set_feedrate_mm_s(10);
      pass->set_spindle_rpm(kRpm);
      total += d;
    }
    p.set_total_depth_mm(total);
    p.set_approach_mm(kApproach_mm);
    p.set_revision(revision_);
    return p;
  }

  void publish_program() { wire_.programs.publish(id_, config_id_, program()); }

  void publish_config() {
    config::SupervisorConfig c;
    c.set_config_id(config_id_);
    c.set_variant(variant_);
    c.set_grafcet_name(variant_ == config::SMC_II ? "smc2" : "smc1");
    c.set_grafcet_text(grafcet_text_);
    const char* modules = variant_ == config::SMC_II ? "ABCDEFGHIJK" : "ABCIJL";
    for (const char* m = modules; *m != '\0'; ++m) c.add_modules(std::string(1, *m));
    auto* machine = c.mutable_machine();
    machine->set_machine_id(id_);
    machine->set_max_spindle_power_w(745.7);
    machine->set_max_feedrate_mm_s(36);
    machine->set_max_spindle_rpm(3000);
    auto* op = c.mutable_operation();
    op->set_teeth(4);
    op->set_cutter_radius_mm(25);
    op->set_sample_period_s(0.0005);
    op->set_fast_period_s(0.01);
    op->set_slow_period_s(0.04);
    op->set_contact_threshold_n(50);
    op->set_force_reference_n(kForceReference_n);
    op->set_suppression_hold_s(kSuppressionHold_s);
    *c.mutable_program() = program();
    c.set_explanation(job_ ? job_->explanation : std::string());
    wire_.configs.publish(id_, config_id_, c);
  }

  void publish_job(const JobInfo& j) {
    config::JobStatus s;
    auto* job = s.mutable_job();
    job->set_job_id(j.id);
    job->set_part_id(j.part);
    job->set_material("6061-T6");
    job->set_tool_id("FM25-4T");
    job->set_machine_id(id_);
    job->set_depth_mm(2);
    job->set_feedrate_mm_s(10);
    job->set_spindle_rpm(kRpm);
    s.set_state(j.state);
    s.set_variant(j.variant);
    s.set_explanation(j.explanation);
    s.set_machine_id(id_);
    s.set_passes_planned(static_cast<std::uint32_t>(j.planned.size()));
    const bool current = job_ && job_->id == j.id;
    s.set_pass_index(current ? static_cast<std::uint32_t>(std::min(pass_index_, passes_.size() - 1))
                             : 0U);
    s.set_pass_count(current ? static_cast<std::uint32_t>(passes_.size())
                             : static_cast<std::uint32_t>(j.planned.size()));
    s.set_fraction_done(j.state == config::JOB_DONE ? 1.0 : current ? fraction_done() : 0.0);
    s.set_chatter_events(j.chatter_events);
    s.set_attempt(1);
    s.set_updated_unix_ms(unix_ms());
    s.set_reason(j.state == config::JOB_PLANNED   ? "planned; waiting for " + id_
                 : j.state == config::JOB_RUNNING ? "running on " + id_
                                                  : "program complete");
    if (j.state == config::JOB_DONE) {
      auto* r = s.mutable_result();
      r->set_config_id(config_id_);
      r->set_variant(j.variant);
      r->set_completed(true);
      r->set_cycle_time_s(j.end_s - j.start_s);
      r->set_depth_removed_mm(2);
      r->set_passes_planned(static_cast<std::uint32_t>(j.planned.size()));
      r->set_passes_completed(static_cast<std::uint32_t>(passes_.size()));
      r->set_program_rewrites(j.rewrites);
      r->set_force_reference_n(kForceReference_n);
      r->set_peak_force_n(j.peak_force);
      r->set_peak_force_violation_pct(100 * (j.peak_force - kForceReference_n) / kForceReference_n);
      r->set_chatter_events(j.chatter_events);
      r->set_feed_hold_s(j.feed_hold_s);
    }
    wire_.jobs.publish(j.id, j.id, s);
  }

  std::string id_;
  config::SmcVariant variant_;
  std::string grafcet_text_;
  const FakeCellOptions& options_;
  Wire& wire_;
  grafcet::Engine engine_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
  int a_ = -1, b_ = -1, c_ = -1, d_ = -1, e_ = -1;
  std::array<int, 64> action_bit_{};

  std::deque<JobInfo> queue_;
  std::optional<JobInfo> job_;
  int job_counter_ = 0;
  std::string config_id_;
  std::vector<double> passes_;
  std::size_t pass_index_ = 0;
  std::uint32_t revision_ = 0;

  Phase phase_ = Phase::kIdle;
  double now_s_ = 0;
  double idle_left_s_;
  double retract_left_s_ = 0;
  double x_mm_ = 0;
  double fpt_ = 0.1;
  double in_cut_s_ = 0;
  double f_y_ = 0;
  double chatter_amp_ = 0;
  double phase_noise_ = 0;
  double suppression_s_ = 0;
  int confirm_ = 0;
  bool chattered_ = false;
  bool chatter_flag_ = false;
  bool contact_ = false;
  bool feed_hold_ = false;
  bool pulse_c_ = false, pulse_d_ = false, pulse_e_ = false;
  bool pulse_d_sent_ = false;
  smc_data_ChatterSource chatter_source_ = smc_data_CHATTER_AUTOMATIC;

  std::uint64_t steps_ = 0;
  std::uint32_t modules_ = 0;
  std::uint32_t inputs_ = 0;
  bool situation_dirty_ = true;
  std::uint32_t revolution_ = 0;
  std::uint32_t situation_seq_ = 0;
  std::uint32_t progress_seq_ = 0;
  std::uint64_t chatter_event_id_ = 0;
  smc_data_EdgeState last_state_ = smc_data_EDGE_FAULT;
};

}  // namespace

int run_fake_cell(const FakeCellOptions& options, const std::atomic<bool>& stop) {
  if (options.mills < 1 || options.mills > 100) throw std::invalid_argument("--mills: 1..100");
  const std::string smc2 = read_text(options.grafcet_dir + "/smc2.grafcet");
  const std::string smc1 = read_text(options.grafcet_dir + "/smc1.grafcet");
  Wire w(options);
  std::vector<std::unique_ptr<FakeMill>> mills;
  for (int i = 1; i <= options.mills; ++i) {
    const bool two = options.all_smc2 || i % 2 == 1;
    mills.push_back(std::make_unique<FakeMill>(options.prefix + std::to_string(i), i,
                                               two ? config::SMC_II : config::SMC_I,
                                               two ? smc2 : smc1, options, w));
  }
  std::printf("ready %d mills\n", options.mills);
  std::fflush(stdout);

  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::microseconds(40000);
  const auto start = Clock::now();
  auto next = start;
  while (!stop.load()) {
    next += period;
    std::this_thread::sleep_until(next);
    const double now_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (options.duration_s > 0 && now_s >= options.duration_s) break;
    w.commands.take([&](const smc_data_OperatorCommand& c, const tr::SampleInfo& info) {
      if (!info.valid_data) return;
      const std::string mill = wire::get_string(c.machine_id);
      for (auto& m : mills) {
        if (m->id() != mill) continue;
        m->command(static_cast<smc_data_OperatorAction>(c.action));
        std::printf("command %s %s %s %llu\n", mill.c_str(),
                    smc::wire::operator_action_name(c.action),
                    wire::get_string(c.operator_name).c_str(),
                    static_cast<unsigned long long>(c.command_id));
        std::fflush(stdout);
      }
    });
    for (auto& m : mills) m->tick(now_s);
    if (Clock::now() > next + 4 * period) next = Clock::now();  // fell behind: do not burst
  }
  return 0;
}

}  // namespace smc::dashboard::testing
