#include "net.hpp"

#include <bit>

namespace smc::grafcet::detail {
namespace {

// Spreads the low bits of `index` over the set bits of `mask`.
Mask deposit(std::uint64_t index, Mask mask) {
  Mask out = 0;
  for (Mask m = mask; m != 0; m &= m - 1, index >>= 1)
    if ((index & 1u) != 0) out |= m & (~m + 1);
  return out;
}

// Recognises, from its truth table, a receptivity over one operand word that
// is a constant, a conjunction or a disjunction of literals.
void classify(const Expression& e, NetTransition& t) {
  int word = -1;
  for (std::size_t w = 0; w < kOperandCount; ++w) {
    if (e.reads[w] == 0) continue;
    if (word >= 0) return;  // several words: the stack machine
    word = static_cast<int>(w);
  }
  const Mask care = word < 0 ? 0 : e.reads[static_cast<std::size_t>(word)];
  const int n = std::popcount(care);
  if (n > 12) return;
  std::size_t ones = 0;
  Mask one_row = 0;
  Mask zero_row = 0;
  for (std::uint64_t i = 0; i < (std::uint64_t{1} << n); ++i) {
    Context c{};
    const Mask x = deposit(i, care);
    if (word >= 0) c[static_cast<std::size_t>(word)] = x;
    if (evaluate(e, c)) {
      ++ones;
      one_row = x;
    } else {
      zero_row = x;
    }
  }
  const std::size_t rows = std::size_t{1} << n;
  t.operand = static_cast<std::uint8_t>(word < 0 ? 0 : word);
  if (ones == 0 || ones == rows) {  // constant: no bit cared for
    t.code = false;
    t.conjunction = ones == rows;
  } else if (ones == 1) {  // true only on one_row
    t.code = false;
    t.conjunction = true;
    t.care = care;
    t.flip = one_row;
  } else if (ones == rows - 1) {  // false only on zero_row
    t.code = false;
    t.care = care;
    t.flip = zero_row;
  }
}

}  // namespace

Net::Net(const Grafcet& grafcet) {
  const auto steps = grafcet.steps();
  for (std::size_t i = 0; i < steps.size(); ++i) {
    level[i] = steps[i].level_actions;
    impulse[i] = steps[i].impulse_actions;
  }
  initial = grafcet.initial_steps();
  transitions.reserve(grafcet.transitions().size());
  for (const Transition& t : grafcet.transitions()) {
    NetTransition nt;
    nt.pre = t.preceding;
    nt.post = t.following;
    nt.begin = static_cast<std::uint32_t>(code.size());
    code.insert(code.end(), t.receptivity.code.begin(), t.receptivity.code.end());
    nt.end = static_cast<std::uint32_t>(code.size());
    classify(t.receptivity, nt);
    transitions.push_back(nt);
  }
  for (std::size_t s = 0; s < kMaxSteps; ++s) {
    by_step_begin[s] = static_cast<std::uint32_t>(by_step.size());
    for (std::size_t i = 0; i < transitions.size(); ++i)
      if (transitions[i].pre != 0 &&
          static_cast<std::size_t>(std::countr_zero(transitions[i].pre)) == s)
        by_step.push_back(static_cast<std::uint32_t>(i));
  }
  by_step_begin[kMaxSteps] = static_cast<std::uint32_t>(by_step.size());
  for (const CheckingOrder& o : grafcet.orders()) {
    NetOrder no;
    no.step = Mask{1} << o.step;
    no.begin = static_cast<std::uint32_t>(order_items.size());
    for (std::size_t t : o.transitions) order_items.push_back(static_cast<std::uint32_t>(t));
    no.end = static_cast<std::uint32_t>(order_items.size());
    orders.push_back(no);
  }
}

}  // namespace smc::grafcet::detail

namespace smc::grafcet::detail {

bool run(const Instruction* pc, const Instruction* end, const Mask* context) noexcept {
  using Op = Instruction::Op;
  std::uint64_t s = 0;
  for (; pc != end; ++pc) {
    switch (pc->op) {
      case Op::kFalse:
        s <<= 1;
        break;
      case Op::kTrue:
        s = (s << 1) | 1u;
        break;
      case Op::kLoad:
        s = (s << 1) | ((context[static_cast<std::uint8_t>(pc->operand)] >> pc->bit) & 1u);
        break;
      case Op::kNot:
        s ^= 1u;
        break;
      case Op::kAnd: {
        const std::uint64_t t = s & 1u;
        s >>= 1;
        s &= t | ~std::uint64_t{1};
        break;
      }
      case Op::kOr: {
        const std::uint64_t t = s & 1u;
        s >>= 1;
        s |= t;
        break;
      }
      case Op::kImplies: {
        const std::uint64_t t = s & 1u;
        s >>= 1;
        s ^= 1u;
        s |= t;
        break;
      }
      case Op::kEquiv: {
        const std::uint64_t t = s & 1u;
        s >>= 1;
        s ^= t ^ 1u;
        break;
      }
    }
  }
  return (s & 1u) != 0;
}

void apply_orders(const Net& net, RoundResult& r, std::uint32_t* fired) noexcept {
  bool suppressed = false;
  for (const NetOrder& o : net.orders) {
    if ((o.step & r.deactivated) == 0) continue;
    bool found = false;
    for (std::uint32_t k = o.begin; k < o.end; ++k) {
      const std::uint32_t candidate = net.order_items[k];
      for (std::uint32_t j = 0; j < r.fired; ++j) {
        if (fired[j] != candidate) continue;
        if (found) {
          fired[j] = fired[--r.fired];
          suppressed = true;
        }
        found = true;
        break;
      }
    }
  }
  if (!suppressed) return;
  const NetTransition* t = net.transitions.data();
  r.deactivated = r.activated = 0;
  for (std::uint32_t j = 0; j < r.fired; ++j) {
    r.deactivated |= t[fired[j]].pre;
    r.activated |= t[fired[j]].post;
  }
}

}  // namespace smc::grafcet::detail
