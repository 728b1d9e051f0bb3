#include "smc/grafcet/engine.hpp"

#include <string>
#include <vector>

#include "net.hpp"
#include "smc/grafcet/model.hpp"

namespace smc::grafcet {

struct Engine::Impl {
  Impl(const Grafcet& g, EngineOptions o) : net(g), options(o) {
    fired.resize(g.transitions().size() + 1);
    for (const Input& i : g.inputs()) input_names.push_back(i.name);
    for (const Action& a : g.actions()) action_names.push_back(a.name);
    for (const Step& s : g.steps()) step_numbers.push_back(s.number);
    input_mask = input_names.size() >= 64 ? ~Mask{0} : (Mask{1} << input_names.size()) - 1;
  }

  const Evaluation& evaluate(Mask inputs) noexcept {
    inputs &= input_mask;
    if (quiet && inputs == previous_inputs && !pending_initial) {
      // Exactly what a full evaluation would give: its one round would see
      // the context of the previous evaluation's last round, which fired nothing.
      result.changed = false;
      result.impulse_actions = 0;
      result.activated_steps = 0;
      result.rounds = 0;
      result.unstable = false;
      return result;
    }
    Mask start = result.active_steps;
    Mask activated = 0;
    Mask rise = 0;
    Mask fall = 0;
    if (pending_initial) {
      start = net.initial;
      activated = net.initial;
    } else {
      rise = inputs & ~previous_inputs;
      fall = previous_inputs & ~inputs;
    }
    const detail::EvolveResult e =
        detail::evolve(net, start, inputs, rise, fall, options.max_rounds, fired.data(),
                       [](Mask, Mask, const std::uint32_t*, std::uint32_t) { return true; });
    activated |= e.activated;
    result.changed = pending_initial || e.active != result.active_steps;
    if (result.changed) result.level_actions = net.level_actions(e.active);
    result.active_steps = e.active;
    result.activated_steps = activated;
    result.impulse_actions = activated == 0 ? 0 : net.impulse_actions(activated);
    result.rounds = e.rounds;
    result.unstable = e.unstable;
    previous_inputs = inputs;
    pending_initial = false;
    quiet = e.quiet;
    return result;
  }

  void reset() noexcept {
    pending_initial = true;
    quiet = false;
    previous_inputs = 0;
    result = Evaluation{};
    result.active_steps = net.initial;
    result.level_actions = net.level_actions(net.initial);
  }

  detail::Net net;
  EngineOptions options;
  std::vector<std::uint32_t> fired;
  std::vector<std::string> input_names;
  std::vector<std::string> action_names;
  std::vector<std::uint32_t> step_numbers;
  Mask input_mask = 0;
  Mask previous_inputs = 0;
  bool pending_initial = true;
  bool quiet = false;  // the last evaluation ended with nothing firable and no edge
  Evaluation result;
};

namespace {
template <class Names, class Key>
int find(const Names& names, const Key& name) noexcept {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}
}  // namespace

Engine::Engine(const Grafcet& grafcet, EngineOptions options)
    : impl_(std::make_unique<Impl>(grafcet, options)) {
  impl_->reset();
}
Engine::~Engine() = default;
Engine::Engine(Engine&&) noexcept = default;
Engine& Engine::operator=(Engine&&) noexcept = default;

int Engine::input_index(std::string_view name) const noexcept {
  return find(impl_->input_names, name);
}
int Engine::action_index(std::string_view name) const noexcept {
  return find(impl_->action_names, name);
}
int Engine::step_index(std::uint32_t number) const noexcept {
  return find(impl_->step_numbers, number);
}
std::size_t Engine::num_inputs() const noexcept { return impl_->input_names.size(); }
std::size_t Engine::num_actions() const noexcept { return impl_->action_names.size(); }
std::size_t Engine::num_steps() const noexcept { return impl_->step_numbers.size(); }
std::uint32_t Engine::step_number(std::size_t index) const noexcept {
  return index < impl_->step_numbers.size() ? impl_->step_numbers[index] : 0;
}
std::string_view Engine::input_name(std::size_t index) const noexcept {
  return index < impl_->input_names.size() ? std::string_view(impl_->input_names[index])
                                           : std::string_view();
}
std::string_view Engine::action_name(std::size_t index) const noexcept {
  return index < impl_->action_names.size() ? std::string_view(impl_->action_names[index])
                                            : std::string_view();
}
Mask Engine::initial_steps() const noexcept { return impl_->net.initial; }

const Evaluation& Engine::evaluate(std::uint64_t inputs) noexcept {
  return impl_->evaluate(inputs);
}
void Engine::reset() noexcept { impl_->reset(); }
const Evaluation& Engine::last() const noexcept { return impl_->result; }

}  // namespace smc::grafcet
