#include <spdlog/spdlog.h>

#include "bridge.hpp"
#include "smc/documents/load.hpp"

namespace smc::edge {

void EdgeService::Impl::use_mill_model(smc::config::SupervisorConfig& cfg) const {
  if (opt.mill_model_file.empty()) return;
  smc::config::MillingModel own;
  smc::documents::load(opt.mill_model_file, own);
  if (cfg.milling_model().has_cutter()) *own.mutable_cutter() = cfg.milling_model().cutter();
  if (cfg.milling_model().has_workpiece())
    *own.mutable_workpiece() = cfg.milling_model().workpiece();
  *cfg.mutable_milling_model() = own;
}

std::string EdgeService::Impl::check(smc::config::SupervisorConfig& cfg) {
  if (cfg.machine().machine_id() != opt.machine_id) {
    return "supervisor_config.machine.machine_id: '" + cfg.machine().machine_id() +
           "' is not this edge ('" + opt.machine_id + "')";
  }
  try {
    EdgeConfig ec = edge_config_from_proto(cfg);
    use_mill_model(cfg);
    SimulatedMill probe(cfg.milling_model(), cfg.simulation(), ec.params.sample_period_s);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

void EdgeService::Impl::take_configs() {
  config_reader.take(
      [&](const std::string& key, const smc::config::SupervisorConfig& doc) {
        if (key != opt.machine_id) return;
        smc::config::SupervisorConfig cfg = doc;
        const std::string why = check(cfg);
        if (!why.empty()) {
          spdlog::error("{}: configuration '{}' rejected: {}", opt.machine_id, cfg.config_id(),
                        why);
          message = "configuration '" + cfg.config_id() + "' rejected: " + why.substr(0, 90);
          publish_status();
          return;
        }
        if (job) {
          pending = cfg;
          spdlog::info("{}: configuration '{}' accepted; in force after job {}", opt.machine_id,
                       cfg.config_id(), job->assignment.job_id());
          return;
        }
        config = cfg;
        set_state(smc_data_EDGE_CONFIGURED, "configuration '" + cfg.config_id() + "' in force");
      },
      [&](const tr::EnvelopeRejection& e) {
        if (e.key != opt.machine_id) return;
        spdlog::error("{}: configuration rejected: {}", opt.machine_id, e.message);
        message = std::string("configuration rejected (") + tr::to_string(e.fault) +
                  "): " + e.message.substr(0, 80);
        publish_status();
      });
}

}  // namespace smc::edge
