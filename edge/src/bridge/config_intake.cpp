#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include "bridge.hpp"
#include "smc/documents/load.hpp"
#include "smc/supervision/gcode.hpp"
#include "smc/supervision/parameters.hpp"
#include "smc/wire/limits.hpp"

namespace smc::edge {

static_assert(supervision::kMaxConfigIdLength == smc::wire::kConfigIdMax);
static_assert(supervision::kMaxConfigIdLength <= smc::wire::kDocumentIdMax);

// ------------------------------------------------------ the intake thread --

ConfigIntake::ConfigIntake(Check check, std::function<void()> checked)
    : check_(std::move(check)), checked_(std::move(checked)), thread_([this] { run(); }) {}

ConfigIntake::~ConfigIntake() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void ConfigIntake::submit(smc::config::SupervisorConfig cfg) {
  {
    std::lock_guard lock(mu_);
    waiting_ = std::move(cfg);
  }
  cv_.notify_all();
}

std::deque<ConfigIntake::Verdict> ConfigIntake::take_verdicts() {
  std::lock_guard lock(mu_);
  return std::exchange(verdicts_, {});
}

bool ConfigIntake::idle() const {
  std::lock_guard lock(mu_);
  return !waiting_ && !busy_;
}

void ConfigIntake::run() {
  // Below the loop and the comms thread: checking a configuration may take
  // hundreds of milliseconds of CPU and must never take it from them (where
  // the loop is not SCHED_FIFO, e.g. paced simulation).
  (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
  std::unique_lock lock(mu_);
  while (true) {
    cv_.wait(lock, [&] { return stop_ || waiting_.has_value(); });
    if (stop_) return;
    Verdict v{std::move(*waiting_), {}};
    waiting_.reset();
    busy_ = true;
    lock.unlock();
    try {
      v.why = check_(v.config);
    } catch (const std::exception& e) {
      v.why = e.what();
    }
    lock.lock();
    busy_ = false;
    verdicts_.push_back(std::move(v));
    lock.unlock();
    checked_();
    lock.lock();
  }
}

// ------------------------------------------------------- the comms side --

std::unique_ptr<SimulatedMill> EdgeService::Impl::simulated_mill(
    const smc::config::SupervisorConfig& cfg, double sample_period_s) const {
  check_wideband_channel_agrees(cfg);
  smc::config::MillingModel model = cfg.milling_model();
  smc::config::SimulatedMill sim = cfg.simulation();
  for (const auto& b : opt.tooth_breaks) {
    auto* t = sim.add_tooth_breaks();
    t->set_tooth(b.tooth);
    t->set_at_s(b.at_s);
    t->set_edge_loss_mm(b.edge_loss_mm);
  }
  if (!opt.mill_model_file.empty()) {
    smc::config::MillingModel own;
    smc::documents::load(opt.mill_model_file, own);
    use_plant_model(model, std::move(own));
  }
  return std::make_unique<SimulatedMill>(model, sim, sample_period_s);
}

// Runs on the intake thread: reads only `opt` (fixed) and its argument.
std::string EdgeService::Impl::check(const smc::config::SupervisorConfig& cfg) {
  if (cfg.machine().machine_id() != opt.machine_id) {
    return "supervisor_config.machine.machine_id: '" + cfg.machine().machine_id() +
           "' is not this edge ('" + opt.machine_id + "')";
  }
  try {
    EdgeConfig ec = edge_config_from_proto(cfg);
    if (opt.drive == "linuxcnc") {
      // The plant is the machine: no model of it is needed, but the
      // program must render as G-code for it (cutter, part, feed clamp).
      supervision::FixedProgram p = ec.program;
      (void)supervision::render_gcode(p, supervision::cut_geometry(cfg));
      return {};
    }
    (void)simulated_mill(cfg, ec.params.sample_period_s);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

void EdgeService::Impl::refuse(const std::string& config_id, const std::string& why) {
  spdlog::error("{}: configuration '{}' refused: {}", opt.machine_id, config_id, why);
  // One line, whole up to the field's size (every problem, "; " between them).
  std::string line;
  for (char c : why) {
    if (c == '\n') {
      line += "; ";
    } else if (c != '\r') {
      line += c;
    }
  }
  if (line.size() > smc::wire::kRefusalMax) {
    line.resize(smc::wire::kRefusalMax - 3);
    line += "...";
  }
  refused_config_id = config_id;
  refusal = line;
  // The status message keeps its short form; the whole reason is `refusal`.
  message = "configuration '" + config_id + "' rejected: " + line;
  if (message.size() > smc::wire::kStatusMessageMax) {
    message.resize(smc::wire::kStatusMessageMax - 3);
    message += "...";
  }
  publish_status();
}

void EdgeService::Impl::take_configs() {
  config_reader.take(
      [&](const std::string& key, const smc::config::SupervisorConfig& doc) {
        if (key != opt.machine_id) return;
        intake->submit(doc);  // checked off this thread; the verdict comes back
      },
      [&](const tr::EnvelopeRejection& e) {
        if (e.key != opt.machine_id) return;
        refuse(e.document_id, std::string("envelope ") + tr::to_string(e.fault) + ": " + e.message);
      });
}

void EdgeService::Impl::apply_checked_configs() {
  for (auto& v : intake->take_verdicts()) {
    smc::config::SupervisorConfig& cfg = v.config;
    if (!v.why.empty()) {
      refuse(cfg.config_id(), v.why);
      continue;
    }
    if (smc::supervision::chatter_detector_without_structure(cfg)) {
      spdlog::warn(
          "{}: configuration '{}' runs module E with no structure in y "
          "(milling_model.structure.tool_y, part_y), so E judges the force spectrum alone; "
          "give it the machine's structure (a tap test) for its vibration estimate",
          opt.machine_id, cfg.config_id());
    }
    if (const auto w = smc::supervision::wideband_channel_warning(cfg); !w.empty()) {
      spdlog::warn("{}: configuration '{}': {}", opt.machine_id, cfg.config_id(), w);
    }
    if (job) {
      pending = cfg;
      spdlog::info("{}: configuration '{}' accepted; in force after job {}", opt.machine_id,
                   cfg.config_id(), job->assignment.job_id());
      continue;
    }
    config = cfg;
    set_state(smc_data_EDGE_CONFIGURED, "configuration '" + cfg.config_id() + "' in force");
  }
}

}  // namespace smc::edge
