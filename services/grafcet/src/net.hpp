#pragma once
// Internal: the compiled form of a Grafcet shared by the Engine and the
// verifier, so that both evolve a Grafcet with the very same code.

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "smc/grafcet/model.hpp"

namespace smc::grafcet::detail {

// Runs postfix code with the operand stack in the bits of one word. Out of
// line: the common receptivities never need it (NetTransition).
bool run(const Instruction* pc, const Instruction* end, const Mask* context) noexcept;

struct NetTransition {
  // Receptivities over one operand word that are a constant, a conjunction
  // of literals (a b', X4, 1) or a disjunction of literals (c + d, ↑c + ↑d,
  // 0) skip the stack machine; most receptivities of a supervisor are so.
  // With v = (word ^ flip) & care: a conjunction is v == 0 (flip: the bits
  // that must be 1), a disjunction v != 0 (flip: the negated literals).
  Mask pre = 0;
  Mask post = 0;
  Mask care = 0;
  Mask flip = 0;
  std::uint32_t begin = 0;  // receptivity code in Net::code, if `code`
  std::uint32_t end = 0;
  std::uint8_t operand = 0;  // the Operand word read
  bool conjunction = false;
  bool code = true;  // not of the forms above: run the stack machine
};

inline bool receptivity(const NetTransition& t, const Instruction* code,
                        const Mask* context) noexcept {
  if (t.code) return run(code + t.begin, code + t.end, context);
  return (((context[t.operand] ^ t.flip) & t.care) != 0) != t.conjunction;
}

struct NetOrder {
  Mask step = 0;
  std::uint32_t begin = 0;  // in Net::order_items
  std::uint32_t end = 0;
};

struct Net {
  explicit Net(const Grafcet& grafcet);

  Mask level_actions(Mask active) const noexcept {
    Mask out = 0;
    for (Mask m = active; m != 0; m &= m - 1)
      out |= level[static_cast<unsigned>(std::countr_zero(m))];
    return out;
  }
  Mask impulse_actions(Mask activated) const noexcept {
    Mask out = 0;
    for (Mask m = activated; m != 0; m &= m - 1)
      out |= impulse[static_cast<unsigned>(std::countr_zero(m))];
    return out;
  }

  std::vector<NetTransition> transitions;
  // Transition indices grouped by their lowest preceding step s, in
  // by_step[by_step_begin[s], by_step_begin[s + 1]): a round visits only
  // the transitions of active steps.
  std::vector<std::uint32_t> by_step;
  std::array<std::uint32_t, kMaxSteps + 1> by_step_begin{};
  std::vector<Instruction> code;
  std::vector<NetOrder> orders;
  std::vector<std::uint32_t> order_items;
  std::array<Mask, kMaxSteps> level{};
  std::array<Mask, kMaxSteps> impulse{};
  Mask initial = 0;
};

struct RoundResult {
  Mask deactivated = 0;
  Mask activated = 0;
  std::uint32_t fired = 0;  // transitions fired: their indices are fired[0, fired)
};

// Removes from `fired` the transitions a checking order suppresses (among the
// firable transitions leaving an ordered step, all but the first in the
// order) and recomputes the masks. Out of line: rarely needed.
void apply_orders(const Net& net, RoundResult& r, std::uint32_t* fired) noexcept;

// One round: every enabled transition whose receptivity holds, minus those a
// checking order suppresses. `context` holds the Operand words (input, rise,
// fall, step); the indices of the transitions that fire go to `fired`, which
// has room for all of them.
inline RoundResult round(const Net& net, const Mask* context, std::uint32_t* fired) noexcept {
  const Mask active = context[static_cast<std::uint8_t>(Operand::kStep)];
  const NetTransition* t = net.transitions.data();
  const Instruction* code = net.code.data();
  const std::uint32_t* by_step = net.by_step.data();
  RoundResult r;
  for (Mask m = active; m != 0; m &= m - 1) {
    const auto s = static_cast<unsigned>(std::countr_zero(m));
    for (std::uint32_t k = net.by_step_begin[s]; k < net.by_step_begin[s + 1]; ++k) {
      const std::uint32_t i = by_step[k];
      if ((t[i].pre & ~active) != 0 || !receptivity(t[i], code, context)) continue;
      fired[r.fired++] = i;
      r.deactivated |= t[i].pre;
      r.activated |= t[i].post;
    }
  }
  if (r.fired > 1 && !net.orders.empty()) apply_orders(net, r, fired);
  return r;
}

struct EvolveResult {
  Mask active = 0;     // where the evolution ended
  Mask activated = 0;  // steps that became active on the way
  std::uint32_t rounds = 0;
  bool unstable = false;  // max_rounds exhausted
  bool aborted = false;   // the observer asked to stop
  bool quiet = false;     // ended on a round without input edges that fired nothing:
                          // the same inputs again would fire nothing either
};

// The evolution of one evaluation (README "Evolution"). `on_round(before,
// after, fired, count)` sees every round that fires something, before it is
// applied; returning false aborts. `fired` has room for every transition.
// The first round sees the input edges, later rounds none. Stops when
// nothing is firable, when a round after the first leaves the situation
// unchanged, or after max_rounds changing rounds.
template <class OnRound>
EvolveResult evolve(const Net& net, Mask active, Mask inputs, Mask rise, Mask fall,
                    std::uint32_t max_rounds, std::uint32_t* fired, OnRound&& on_round) noexcept {
  Mask context[kOperandCount] = {inputs, rise, fall, active, 0, 0};
  EvolveResult r;
  r.active = active;
  for (bool first = true;; first = false) {
    const RoundResult rd = round(net, context, fired);
    if (rd.fired == 0) {
      r.quiet = (context[static_cast<std::uint8_t>(Operand::kRise)] |
                 context[static_cast<std::uint8_t>(Operand::kFall)]) == 0;
      break;
    }
    const Mask next = (r.active & ~rd.deactivated) | rd.activated;
    if (!on_round(r.active, next, static_cast<const std::uint32_t*>(fired), rd.fired)) {
      r.aborted = true;
      break;
    }
    if (next == r.active && !first) break;
    if (r.rounds == max_rounds) {
      r.unstable = true;
      break;
    }
    r.activated |= next & ~r.active;
    r.active = next;
    ++r.rounds;
    context[static_cast<std::uint8_t>(Operand::kRise)] = 0;
    context[static_cast<std::uint8_t>(Operand::kFall)] = 0;
    context[static_cast<std::uint8_t>(Operand::kStep)] = next;
  }
  return r;
}

}  // namespace smc::grafcet::detail
