#pragma once
// Internal: what the parser reads, before names are resolved (parser.cpp)
// and turned into a Grafcet (builder.cpp).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "smc/grafcet/model.hpp"

namespace smc::grafcet::detail {

struct Node {
  enum class Kind : std::uint8_t {
    kConst,
    kName,
    kImpulse,
    kRise,
    kFall,
    kNot,
    kAnd,
    kOr,
    kImplies,
    kEquiv
  };
  Kind kind = Kind::kConst;
  bool value = false;     // kConst
  std::string_view name;  // kName, kImpulse, kRise, kFall
  SourceLocation where;
  int a = -1;  // operands (node indices)
  int b = -1;
  int depth = 1;  // of the subtree rooted here (bounded by the parser)
};

struct Ast {
  std::vector<Node> nodes;
  int root = -1;
  std::string text;
  SourceLocation where;
};

struct NameDecl {
  std::string name;
  std::string description;
  SourceLocation where;
};

struct NumberRef {
  std::uint64_t number = 0;
  SourceLocation where;
};

struct ActionRef {
  std::string name;
  bool impulse = false;
  SourceLocation where;
};

struct StepDraft {
  NumberRef id;
  bool initial = false;
  std::string label;
  std::vector<ActionRef> actions;
  bool broken = false;  // a syntax error cut the statement short
};

struct TransitionDraft {
  NumberRef id;
  std::vector<NumberRef> preceding;
  std::vector<NumberRef> following;
  Ast receptivity;
  bool broken = false;
};

struct OrderDraft {
  NumberRef step;
  std::vector<NumberRef> transitions;
  SourceLocation where;
  bool broken = false;
};

struct InvariantDraft {
  std::string name;
  SourceLocation where;
  Ast condition;
  std::optional<Ast> next;
  bool broken = false;
};

struct Draft {
  std::optional<NameDecl> grafcet;            // name + title
  std::vector<SourceLocation> extra_grafcet;  // repeated 'grafcet' statements
  std::vector<NameDecl> inputs;
  std::vector<NameDecl> actions;
  std::vector<StepDraft> steps;
  bool step_statement_failed = false;  // a 'step' line did not parse at all
  std::vector<TransitionDraft> transitions;
  std::vector<OrderDraft> orders;
  std::vector<InvariantDraft> invariants;
};

}  // namespace smc::grafcet::detail
