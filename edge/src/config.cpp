#include <cmath>
#include <sstream>

#include "smc/edge/core.hpp"
#include "smc_config.pb.h"

namespace smc::edge {

namespace {

[[noreturn]] void fail(const std::string& field, const std::string& why) {
  throw ConfigError("supervisor_config." + field + ": " + why);
}

std::string num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

}  // namespace

EdgeConfig edge_config_from_proto(const smc::config::SupervisorConfig& cfg) {
  EdgeConfig c;
  c.config_id = cfg.config_id();
  if (c.config_id.empty()) fail("config_id", "is empty; give the configuration a name");
  c.variant = cfg.variant();
  if (cfg.variant() == smc::config::SMC_UNSPECIFIED) {
    fail("variant", "is unspecified; use SMC_NONE, SMC_I or SMC_II");
  }
  c.params = parameters_from_config(cfg);

  for (int i = 0; i < cfg.modules_size(); ++i) {
    const std::string& m = cfg.modules(i);
    if (m.size() != 1 || m[0] < 'A' || m[0] > 'L') {
      fail("modules[" + std::to_string(i) + "]",
           "'" + m + "' is not a module; use the letters A to L of the paper's Table 1");
    }
    c.modules = static_cast<ModuleMask>(c.modules | bit(static_cast<ModuleId>(m[0] - 'A')));
  }
  if ((c.modules & bit(ModuleId::A)) == 0) fail("modules", "must include A (feedrate routine)");
  if ((c.modules & bit(ModuleId::L)) != 0 && !c.params.has_force_model) {
    fail("force_model", "module L needs a force-process model (k_kn, beta, alpha > 0)");
  }
  if ((c.modules & bit(ModuleId::G)) != 0) {
    c.modules = static_cast<ModuleMask>(c.modules | bit(ModuleId::F));  // G invokes F
  }

  const auto& prog = cfg.program();
  if (prog.passes_size() == 0) fail("program.passes", "is empty; give at least one pass");
  if (prog.passes_size() > FixedProgram::kMaxPasses) {
    fail("program.passes", "has " + std::to_string(prog.passes_size()) + " passes; at most " +
                               std::to_string(FixedProgram::kMaxPasses));
  }
  const EdgeParameters& p = c.params;
  for (int i = 0; i < prog.passes_size(); ++i) {
    const auto& ps = prog.passes(i);
    const std::string at = "program.passes[" + std::to_string(i) + "].";
    if (!(ps.depth_mm() > 0 && ps.depth_mm() < 50)) {
      fail(at + "depth_mm", "must be in (0, 50) mm (got " + num(ps.depth_mm()) + ")");
    }
    if (!(ps.spindle_rpm() > 0 && ps.spindle_rpm() <= p.max_spindle_rpm)) {
      fail(at + "spindle_rpm",
           "must be in (0, " + num(p.max_spindle_rpm) + "] (got " + num(ps.spindle_rpm()) + ")");
    }
    if (!(ps.feedrate_mm_s() > 0 && ps.feedrate_mm_s() <= p.max_feedrate_mm_s)) {
      fail(at + "feedrate_mm_s", "must be in (0, " + num(p.max_feedrate_mm_s) +
                                     "] mm/s, the machine's limit (got " + num(ps.feedrate_mm_s()) +
                                     ")");
    }
    const double fpt = p.feed_per_tooth_for(ps.feedrate_mm_s(), ps.spindle_rpm());
    if (fpt > p.max_feed_per_tooth_mm) {
      fail(at + "feedrate_mm_s", num(ps.feedrate_mm_s()) + " mm/s is " + num(fpt) +
                                     " mm/tooth, above the operation's limit of " +
                                     num(p.max_feed_per_tooth_mm) + "; lower the feedrate");
    }
    const double rev_s = 60.0 / ps.spindle_rpm();
    if (std::fabs(rev_s - p.slow_period_s) > p.sample_period_s) {
      fail(at + "spindle_rpm", num(ps.spindle_rpm()) + " rpm is a " + num(rev_s) +
                                   " s revolution, but operation.slow_period_s is " +
                                   num(p.slow_period_s) + "; make them agree");
    }
    PassSpec& spec = c.program.passes[static_cast<size_t>(i)];
    spec.depth_mm = ps.depth_mm();
    spec.feedrate_mm_s = ps.feedrate_mm_s();
    spec.spindle_rpm = ps.spindle_rpm();
  }
  c.program.count = static_cast<uint16_t>(prog.passes_size());
  c.program.revision = prog.revision();

  c.grafcet_name = cfg.grafcet_name().empty() ? c.config_id + ".grafcet" : cfg.grafcet_name();
  c.grafcet_text = cfg.grafcet_text();
  if (c.grafcet_text.empty()) fail("grafcet_text", "is empty; give the operation supervisor");
  // Parse and verify now, so a bad Grafcet is refused before anything runs.
  OperationSupervisor check(c.grafcet_text, c.grafcet_name, c.modules);
  return c;
}

}  // namespace smc::edge
