#include "smc/grafcet/model.hpp"

#include "net.hpp"

namespace smc::grafcet {

bool evaluate(const Expression& expression, const Context& context) noexcept {
  const Instruction* begin = expression.code.data();
  return detail::run(begin, begin + expression.code.size(), context.data());
}

Mask Grafcet::initial_steps() const noexcept {
  Mask m = 0;
  for (std::size_t i = 0; i < p_.steps.size(); ++i)
    if (p_.steps[i].initial) m |= Mask{1} << i;
  return m;
}

int Grafcet::input_index(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < p_.inputs.size(); ++i)
    if (p_.inputs[i].name == name) return static_cast<int>(i);
  return -1;
}

int Grafcet::action_index(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < p_.actions.size(); ++i)
    if (p_.actions[i].name == name) return static_cast<int>(i);
  return -1;
}

int Grafcet::step_index(std::uint32_t number) const noexcept {
  for (std::size_t i = 0; i < p_.steps.size(); ++i)
    if (p_.steps[i].number == number) return static_cast<int>(i);
  return -1;
}

int Grafcet::transition_index(std::uint32_t number) const noexcept {
  for (std::size_t i = 0; i < p_.transitions.size(); ++i)
    if (p_.transitions[i].number == number) return static_cast<int>(i);
  return -1;
}

}  // namespace smc::grafcet
