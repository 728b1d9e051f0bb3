#include <array>
#include <string>

#include "smc/edge/parameters.hpp"
#include "smc/edge/supervisor.hpp"
#include "smc/grafcet/engine.hpp"
#include "smc/grafcet/parser.hpp"
#include "smc/grafcet/verifier.hpp"

namespace smc::edge {

struct OperationSupervisor::Impl {
  grafcet::Grafcet grafcet;
  grafcet::Engine engine;
  std::array<ModuleMask, grafcet::kMaxActions> action_module{};  // action index → module bit
  std::array<int, 5> input_bit{};  // receptivity a..e → the Grafcet's input index, -1 if unused

  explicit Impl(grafcet::Grafcet g) : grafcet(std::move(g)), engine(grafcet) {}
};

OperationSupervisor::OperationSupervisor(std::string_view grafcet_text,
                                         std::string_view source_name, ModuleMask allowed) {
  grafcet::ParseResult parsed = grafcet::parse(grafcet_text, source_name);
  if (!parsed.ok()) {
    std::string msg = "operation supervisor: the Grafcet does not parse:";
    for (const auto& d : parsed.errors) msg += "\n  " + d.str();
    throw ConfigError(msg);
  }
  const grafcet::Report report = grafcet::verify(*parsed.grafcet);
  if (!report.ok()) {
    throw ConfigError("operation supervisor: the Grafcet fails verification:\n" +
                      grafcet::format_report(*parsed.grafcet, report));
  }
  impl_ = std::make_unique<Impl>(std::move(*parsed.grafcet));
  const auto& g = impl_->grafcet;
  const std::string where(source_name);
  for (size_t i = 0; i < g.actions().size(); ++i) {
    const std::string& name = g.actions()[i].name;
    if (name.size() != 1 || name[0] < 'A' || name[0] > 'L') {
      throw ConfigError(where + ": action '" + name +
                        "' is not a module; actions must be module letters A to L");
    }
    const auto id = static_cast<ModuleId>(name[0] - 'A');
    if ((allowed & bit(id)) == 0) {
      throw ConfigError(where + ": action '" + name + "' uses module " + name +
                        ", which the configuration's module set does not include");
    }
    impl_->action_module[i] = bit(id);
  }
  impl_->input_bit.fill(-1);
  for (size_t i = 0; i < g.inputs().size(); ++i) {
    const std::string& name = g.inputs()[i].name;
    if (name.size() != 1 || name[0] < 'a' || name[0] > 'e') {
      throw ConfigError(where + ": input '" + name +
                        "' is not a receptivity of the state supervisor (a, b, c, d or e)");
    }
    impl_->input_bit[static_cast<size_t>(name[0] - 'a')] = static_cast<int>(i);
  }
}

OperationSupervisor::~OperationSupervisor() = default;

void OperationSupervisor::reset() noexcept {
  impl_->engine.reset();
  situation_ = Situation{};
}

const Situation& OperationSupervisor::evaluate(uint32_t inputs) noexcept {
  uint64_t in = 0;
  for (size_t r = 0; r < impl_->input_bit.size(); ++r) {
    const int b = impl_->input_bit[r];
    if (b >= 0 && ((inputs >> r) & 1u) != 0) in |= uint64_t{1} << b;
  }
  const grafcet::Evaluation& e = impl_->engine.evaluate(in);
  ModuleMask active = 0, impulses = 0;
  for (uint64_t m = e.level_actions; m != 0; m &= m - 1) {
    active = static_cast<ModuleMask>(active |
                                     impl_->action_module[static_cast<size_t>(__builtin_ctzll(m))]);
  }
  for (uint64_t m = e.impulse_actions; m != 0; m &= m - 1) {
    impulses = static_cast<ModuleMask>(
        impulses | impl_->action_module[static_cast<size_t>(__builtin_ctzll(m))]);
  }
  situation_.active_steps = e.active_steps;
  situation_.active = active;
  situation_.impulses = impulses;
  situation_.inputs = inputs;
  situation_.changed = e.changed;
  situation_.error = e.unstable;
  return situation_;
}

int OperationSupervisor::step_number(int index) const {
  return static_cast<int>(impl_->engine.step_number(static_cast<size_t>(index)));
}

int OperationSupervisor::step_count() const { return static_cast<int>(impl_->engine.num_steps()); }

const std::string& OperationSupervisor::name() const { return impl_->grafcet.name(); }

}  // namespace smc::edge
