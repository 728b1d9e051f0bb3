#include "smc/supervision/config.hpp"

#include <cmath>

#include "smc_config.pb.h"

namespace smc::supervision {

namespace {

using common::number;

}  // namespace

ValidatedConfig validate(const smc::config::SupervisorConfig& cfg, ModuleMask known) {
  common::Diagnostics problems;
  const std::string root = "supervisor_config.";
  ValidatedConfig c;
  c.config_id = cfg.config_id();
  if (c.config_id.empty()) {
    problems.add(root + "config_id", "is empty", "give the configuration a name");
  } else if (c.config_id.size() > kMaxConfigIdLength) {
    problems.add(root + "config_id",
                 common::quote(c.config_id) + " is " + std::to_string(c.config_id.size()) +
                     " characters; the wire carries " + std::to_string(kMaxConfigIdLength),
                 "use a shorter id");
  }
  c.variant = cfg.variant();
  if (cfg.variant() == smc::config::SMC_UNSPECIFIED) {
    problems.add(root + "variant", "is unspecified", "use SMC_NONE, SMC_I, SMC_II or SMC_II_PLUS");
  }
  c.params = read_parameters(cfg, problems);
  const bool params_ok = problems.ok();

  for (int i = 0; i < cfg.modules_size(); ++i) {
    const std::string& m = cfg.modules(i);
    const auto id = module_from_letter(m);
    if (!id || !has(known, *id)) {
      problems.add(root + "modules[" + std::to_string(i) + "]",
                   common::quote(m, 16) + " is not a module",
                   "use the module letters " + letters(known) +
                       " (A to L: the paper's Table 1; M: spindle power monitor)");
      continue;
    }
    c.modules = static_cast<ModuleMask>(c.modules | bit(*id));
  }
  if (!has(c.modules, ModuleId::A)) {
    problems.add(root + "modules", "must include A (feedrate routine)", "add \"A\"");
  }
  if (has(c.modules, ModuleId::L) && !c.params.has_force_model) {
    problems.add(root + "force_model",
                 "module L needs a force-process model (k_kn, beta, alpha > 0)",
                 "give the force model or use module K");
  }
  if (has(c.modules, ModuleId::G)) {
    c.modules = static_cast<ModuleMask>(c.modules | bit(ModuleId::F));  // G invokes F
  }

  const auto& prog = cfg.program();
  if (prog.passes_size() == 0) {
    problems.add(root + "program.passes", "is empty", "give at least one pass");
  }
  if (prog.passes_size() > kMaxPasses) {
    problems.add(root + "program.passes",
                 "has " + std::to_string(prog.passes_size()) + " passes; at most " +
                     std::to_string(kMaxPasses),
                 "take the depth in fewer, deeper passes");
  }
  const Parameters& p = c.params;
  for (int i = 0; i < prog.passes_size() && i < kMaxPasses; ++i) {
    const auto& ps = prog.passes(i);
    const std::string at = root + "program.passes[" + std::to_string(i) + "].";
    if (!(ps.depth_mm() > 0 && ps.depth_mm() < 50)) {
      problems.add(at + "depth_mm", "must be in (0, 50) mm (got " + number(ps.depth_mm()) + ")");
    }
    if (params_ok) {
      if (!(ps.spindle_rpm() > 0 && ps.spindle_rpm() <= p.max_spindle_rpm)) {
        problems.add(at + "spindle_rpm", "must be in (0, " + number(p.max_spindle_rpm) + "] (got " +
                                             number(ps.spindle_rpm()) + ")");
      }
      if (!(ps.feedrate_mm_s() > 0 && ps.feedrate_mm_s() <= p.max_feedrate_mm_s)) {
        problems.add(at + "feedrate_mm_s", "must be in (0, " + number(p.max_feedrate_mm_s) +
                                               "] mm/s, the machine's limit (got " +
                                               number(ps.feedrate_mm_s()) + ")");
      }
      const double fpt = p.feed_per_tooth_for(ps.feedrate_mm_s(), ps.spindle_rpm());
      if (fpt > p.max_feed_per_tooth_mm) {
        problems.add(at + "feedrate_mm_s",
                     number(ps.feedrate_mm_s()) + " mm/s is " + number(fpt) +
                         " mm/tooth, above the operation's limit of " +
                         number(p.max_feed_per_tooth_mm),
                     "lower the feedrate");
      }
      if (!(ps.force_reference_n() >= 0 && std::isfinite(ps.force_reference_n()))) {
        problems.add(at + "force_reference_n",
                     "must be >= 0 N (got " + number(ps.force_reference_n()) + ")",
                     "use 0 to derive it from the power limit");
      }
      if (ps.spindle_rpm() > 0 && ps.spindle_rpm() < p.min_spindle_rpm) {
        problems.add(at + "spindle_rpm",
                     number(ps.spindle_rpm()) + " rpm is below the machine's supervised range (" +
                         number(p.min_spindle_rpm) + " rpm)",
                     "raise the speed, or lower machine.min_spindle_rpm");
      }
    }
    PassSpec& spec = c.program.passes[static_cast<size_t>(i)];
    spec.depth_mm = ps.depth_mm();
    spec.feedrate_mm_s = ps.feedrate_mm_s();
    spec.spindle_rpm = ps.spindle_rpm();
    spec.force_reference_n = ps.force_reference_n();
  }
  c.program.count = static_cast<uint16_t>(std::min(prog.passes_size(), kMaxPasses));
  c.program.revision = prog.revision();

  c.grafcet_name = cfg.grafcet_name().empty() ? c.config_id + ".grafcet" : cfg.grafcet_name();
  c.grafcet_text = cfg.grafcet_text();
  if (c.grafcet_text.empty()) {
    problems.add(root + "grafcet_text", "is empty", "give the operation supervisor");
  }
  if (!problems.ok()) throw ConfigError(std::move(problems));
  // Parse, bind and verify last: it is the only costly check.
  c.grafcet =
      std::make_shared<const BoundGrafcet>(bind_grafcet(c.grafcet_text, c.grafcet_name, c.modules));
  return c;
}

}  // namespace smc::supervision
