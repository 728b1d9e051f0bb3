#pragma once
// The Grafcet model (IEC 60848): steps, transitions, actions, checking orders
// and invariants, as produced by the parser (parser.hpp). A Grafcet is
// immutable and always complete: only the parser builds one, and only when
// the text had no error. The engine (engine.hpp) and the verifier
// (verifier.hpp) take it as input. Nothing here runs in the real-time loop.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "smc/grafcet/types.hpp"

namespace smc::grafcet {

// 1-based line and column (columns count Unicode code points).
struct SourceLocation {
  std::uint32_t line = 0;
  std::uint32_t column = 0;
};

// What a compiled expression reads. An evaluation context is one Mask per
// operand, indexed by the enumerator's value.
enum class Operand : std::uint8_t {
  kInput = 0,          // input values of this evaluation
  kRise = 1,           // inputs that went 0 -> 1 since the previous evaluation
  kFall = 2,           // inputs that went 1 -> 0
  kStep = 3,           // active steps (step variables X1, X2, ...)
  kLevelAction = 4,    // level actions active (invariants only)
  kImpulseAction = 5,  // impulse actions fired (invariants only)
};
inline constexpr std::size_t kOperandCount = 6;
using Context = std::array<Mask, kOperandCount>;

// One instruction of a Boolean expression in postfix form. The evaluator
// keeps its operand stack in the bits of one 64-bit word, so an expression
// may need at most 64 stack entries (the parser checks).
struct Instruction {
  enum class Op : std::uint8_t { kFalse, kTrue, kLoad, kNot, kAnd, kOr, kImplies, kEquiv };
  Op op = Op::kFalse;
  Operand operand = Operand::kInput;  // kLoad only
  std::uint8_t bit = 0;               // kLoad only
};

struct Expression {
  std::vector<Instruction> code;  // postfix
  std::string text;               // as written, whitespace collapsed
  SourceLocation where;
  Context reads{};  // the bits of each operand the expression reads
};

// Evaluates a compiled expression. No allocation.
bool evaluate(const Expression& expression, const Context& context) noexcept;

struct Input {
  std::string name;
  std::string description;
  SourceLocation where;
};

struct Action {
  std::string name;  // e.g. "L": the edge maps actions to modules by name
  std::string description;
  SourceLocation where;  // declaration, or first use in a step
};

struct Step {
  std::uint32_t number = 0;  // the designer's number (X<number>)
  std::string label;
  bool initial = false;
  Mask level_actions = 0;    // active while the step is active
  Mask impulse_actions = 0;  // fired once when the step becomes active
  SourceLocation where;
};

struct Transition {
  std::uint32_t number = 0;  // the designer's number, (n) on the chart
  Mask preceding = 0;        // steps
  Mask following = 0;        // steps
  Expression receptivity;    // over inputs, their edges and step variables
  SourceLocation where;
};

// Among the firable transitions leaving `step`, only the first in
// `transitions` order fires.
struct CheckingOrder {
  std::size_t step = 0;                  // step index
  std::vector<std::size_t> transitions;  // transition indices, first wins
  SourceLocation where;
};

// `condition` alone: holds in every reachable stable situation.
// With `next`: from every reachable stable situation and for every input
// valuation, if `condition` holds before the evolution (steps and level
// actions of the situation left, the new inputs), `next` holds in the stable
// situation reached (its steps and level actions, the same inputs, the
// impulse actions fired on the way).
struct Invariant {
  std::string name;
  Expression condition;
  std::optional<Expression> next;
  SourceLocation where;
};

class Grafcet {
 public:
  struct Parts {
    std::string name;
    std::string title;
    std::string source;  // file name the text came from
    std::vector<Input> inputs;
    std::vector<Action> actions;
    std::vector<Step> steps;
    std::vector<Transition> transitions;
    std::vector<CheckingOrder> orders;
    std::vector<Invariant> invariants;
  };

  const std::string& name() const noexcept { return p_.name; }
  const std::string& title() const noexcept { return p_.title; }
  const std::string& source() const noexcept { return p_.source; }
  std::span<const Input> inputs() const noexcept { return p_.inputs; }
  std::span<const Action> actions() const noexcept { return p_.actions; }
  std::span<const Step> steps() const noexcept { return p_.steps; }
  std::span<const Transition> transitions() const noexcept { return p_.transitions; }
  std::span<const CheckingOrder> orders() const noexcept { return p_.orders; }
  std::span<const Invariant> invariants() const noexcept { return p_.invariants; }

  Mask initial_steps() const noexcept;

  // Index lookups; -1 when unknown.
  int input_index(std::string_view name) const noexcept;
  int action_index(std::string_view name) const noexcept;
  int step_index(std::uint32_t number) const noexcept;
  int transition_index(std::uint32_t number) const noexcept;

 private:
  friend class GrafcetBuilder;  // the parser, src/parser.cpp
  explicit Grafcet(Parts parts) : p_(std::move(parts)) {}
  Parts p_;
};

}  // namespace smc::grafcet
