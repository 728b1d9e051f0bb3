// Modules are scheduled by what they declare (period, samples, signals
// written, after the supervisor) in the registry's data-flow order, and
// their declared writes are checked: at configuration (one owner per signal)
// and, when asked, at every run. A test-only module shows what adding a
// module takes: its class, a registry entry, its letter in the module set
// and the Grafcet's actions — nothing in the core.

#include <gtest/gtest.h>

#include <string>

#include "edge_test_config.hpp"
#include "smc/edge/core.hpp"
#include "smc/edge/runner.hpp"
#include "smc/edge/sim_mill.hpp"
#include "smc/supervision/config.hpp"
#include "smc_config.pb.h"

using namespace smc::edge;

namespace {

constexpr auto kM = static_cast<ModuleId>(15);  // P: the first letter the project does not use

// Test-only module P: runs once per revolution after I and J, writes nothing.
// Records what it saw, so the test can check when it ran.
struct Seen {
  int updates = 0;
  int updates_without_fresh_f_y = 0;  // I must have run earlier in the same tick
};
Seen g_seen;

class RevolutionWitness final : public Module {
 public:
  RevolutionWitness() noexcept : Module(kM) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return 0; }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override {}
  Status update(Signals& s) noexcept override {
    ++g_seen.updates;
    if (!s.f_y_updated) ++g_seen.updates_without_fresh_f_y;
    return Status::kOk;
  }
};

// Test-only module P that writes a signal it does not declare.
class Trespasser final : public Module {
 public:
  Trespasser() noexcept : Module(kM) {}
  Period period() const noexcept override { return Period::kRevolution; }
  SignalMask writes() const noexcept override { return 0; }
  void configure(const EdgeParameters&) override {}
  void reset() noexcept override {}
  Status update(Signals& s) noexcept override {
    s.contact = !s.contact;  // J's signal
    return Status::kOk;
  }
};

template <class M>
ModuleRegistry with_module_m() {
  ModuleRegistry r = paper_modules();
  // Data-flow position: after J (it reads I's fresh F_Y).
  for (size_t i = 0; i < r.size(); ++i) {
    if (r[i].id == ModuleId::J) {
      r.insert(r.begin() + static_cast<std::ptrdiff_t>(i) + 1,
               ModuleEntry{kM, [] { return std::unique_ptr<Module>(std::make_unique<M>()); }});
      break;
    }
  }
  return r;
}

// SMC I with module P active while in contact (step 4).
smc::config::SupervisorConfig smc1_with_m() {
  auto cfg = test::shipped_config("smc1.textproto");
  cfg.add_modules("P");
  std::string g = cfg.grafcet_text();
  const std::string action_l = "action L \"model-based force controller\"\n";
  const std::string step4 = "A, B, I, J, L\n";
  g.replace(g.find(action_l), action_l.size(), action_l + "action P \"test-only witness\"\n");
  g.replace(g.find(step4), step4.size(), "A, B, I, J, L, P\n");
  cfg.set_grafcet_text(g);
  return cfg;
}

}  // namespace

TEST(ModuleDeclarations, PaperRunsStayWithinTheirDeclaredWrites) {
  for (const char* name :
       {"smc1.textproto", "smc1_guarded.textproto", "smc2.textproto", "smc2_plus.textproto"}) {
    const auto raw = test::shipped_config(name);
    const EdgeConfig cfg = edge_config_from_proto(raw);
    SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
    EdgeCore core(cfg, mill);
    core.set_check_declarations(true);
    core.start();
    RunOptions opts;
    opts.keep_samples = false;
    const RunResult run = run_virtual(core, opts);
    EXPECT_TRUE(run.completed) << name;
    for (const auto& e : run.events) {
      EXPECT_NE(e.kind, EventKind::kFault)
          << name << ": module " << int{e.module} << " wrote undeclared signals " << e.value;
    }
  }
}

TEST(ModuleDeclarations, AnUndeclaredWriteFaultsTheModule) {
  const ModuleRegistry reg = with_module_m<Trespasser>();
  const auto raw = smc1_with_m();
  const EdgeConfig cfg = edge_config_from_proto(raw, reg);
  SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
  EdgeCore core(cfg, mill, reg);
  core.set_check_declarations(true);
  core.start();
  RunOptions opts;
  opts.keep_samples = false;
  opts.max_time_s = 6;  // past the first contact
  const RunResult run = run_virtual(core, opts);
  bool faulted = false;
  for (const auto& e : run.events) {
    if (e.kind != EventKind::kFault) continue;
    faulted = true;
    EXPECT_EQ(e.fault, Fault::kModuleError);
    EXPECT_EQ(e.module, static_cast<int>(kM));
    EXPECT_EQ(static_cast<SignalMask>(e.value), mask(Signal::kContact));
    break;
  }
  EXPECT_TRUE(faulted);
  EXPECT_TRUE(core.fault_hold());
}

TEST(ModuleDeclarations, TwoOwnersOfOneSignalAreRefused) {
  auto cfg = test::shipped_config("smc2.textproto");
  cfg.add_modules("L");
  cfg.mutable_force_model()->set_k_kn(0.76);
  cfg.mutable_force_model()->set_beta(0.65);
  cfg.mutable_force_model()->set_alpha(0.63);
  try {
    (void)edge_config_from_proto(cfg);
    FAIL() << "accepted K and L together";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("modules K and L both write the signal controller_feed"),
              std::string::npos)
        << e.what();
  }
}

TEST(ModuleDeclarations, ATestOnlyModuleRunsAtItsDeclaredPeriodInDataFlowOrder) {
  const ModuleRegistry reg = with_module_m<RevolutionWitness>();
  const auto raw = smc1_with_m();
  // The cell's validation knows only the paper's modules; the edge's knows its registry.
  EXPECT_THROW((void)smc::supervision::validate(raw), ConfigError);
  const EdgeConfig cfg = edge_config_from_proto(raw, reg);
  EXPECT_TRUE(has(cfg.modules, kM));

  g_seen = {};
  SimulatedMill mill(raw.milling_model(), raw.simulation(), cfg.params.sample_period_s);
  EdgeCore core(cfg, mill, reg);
  core.set_check_declarations(true);
  core.start();
  // P runs in a revolution tick when the previous tick's situation enabled it.
  int expected = 0;
  ModuleMask active_before = 0;
  RunOptions opts;
  opts.keep_samples = false;
  opts.on_tick = [&](const EdgeCore& c) {
    if (c.ticks() % static_cast<uint64_t>(cfg.params.samples_per_revolution) == 0 &&
        has(active_before, kM)) {
      ++expected;
    }
    active_before = c.signals().active;
  };
  const RunResult run = run_virtual(core, opts);
  EXPECT_TRUE(run.completed);
  EXPECT_GT(g_seen.updates, 100);  // two 1 mm passes of ~4 s of contact each, 40 ms revolutions
  EXPECT_EQ(g_seen.updates, expected);
  EXPECT_EQ(g_seen.updates_without_fresh_f_y, 0);
  for (const auto& e : run.events) EXPECT_NE(e.kind, EventKind::kFault);
}
