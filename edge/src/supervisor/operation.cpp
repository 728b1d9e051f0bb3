#include <array>
#include <string>

#include "smc/edge/parameters.hpp"
#include "smc/edge/supervisor.hpp"
#include "smc/grafcet/engine.hpp"

namespace smc::edge {

struct OperationSupervisor::Impl {
  std::string name;
  grafcet::Engine engine;
  std::array<ModuleMask, grafcet::kMaxActions> action_module{};  // action index → module bit
  std::array<int, supervision::kReceptivityCount> input_bit{};   // a..e → input index, -1 unused

  explicit Impl(const supervision::BoundGrafcet& b)
      : name(b.grafcet.name()),
        engine(b.grafcet),
        action_module(b.action_module),
        input_bit(b.input_index) {}
};

OperationSupervisor::OperationSupervisor(const supervision::BoundGrafcet& grafcet)
    : impl_(std::make_unique<Impl>(grafcet)) {}

OperationSupervisor::OperationSupervisor(std::string_view grafcet_text,
                                         std::string_view source_name, ModuleMask allowed)
    : OperationSupervisor(supervision::bind_grafcet(grafcet_text, source_name, allowed)) {}

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

const std::string& OperationSupervisor::name() const { return impl_->name; }

}  // namespace smc::edge
