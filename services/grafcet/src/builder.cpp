// Semantics of the Grafcet text format: resolves names and numbers, checks
// the limits and the checking orders, compiles expressions, and builds the
// Grafcet only when nothing at all was wrong.

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "parser_internal.hpp"
#include "smc/grafcet/parser.hpp"

namespace smc::grafcet {

using detail::Ast;
using detail::Node;

Diagnostic::Diagnostic(std::string file_name, SourceLocation at, std::string what)
    : file(std::move(file_name)), location(at) {
  constexpr std::size_t kMaxMessage = 240;
  where = file;
  if (at.line != 0) where += ":" + std::to_string(at.line) + ":" + std::to_string(at.column);
  message = what.size() <= kMaxMessage
                ? std::move(what)
                : what.substr(0, kMaxMessage) + "…(" + std::to_string(what.size()) + " bytes)";
}

std::string Diagnostic::str() const { return where + ": error: " + message; }

namespace {

std::string at(SourceLocation w) { return std::to_string(w.line) + ":" + std::to_string(w.column); }

// What an expression may read.
enum class Scope { kReceptivity, kCondition, kConclusion };

}  // namespace

class GrafcetBuilder {
 public:
  GrafcetBuilder(const detail::Draft& draft, std::string file, std::vector<Diagnostic>& errors)
      : d_(draft), file_(std::move(file)), errors_(errors) {}

  std::optional<Grafcet> build() {
    const std::size_t errors_before = errors_.size();
    header();
    inputs();
    actions();
    steps();
    transitions();
    orders();
    invariants();
    if (errors_.size() != errors_before) return std::nullopt;
    return Grafcet(std::move(p_));
  }

 private:
  void error(SourceLocation where, std::string message) {
    errors_.push_back({file_, where, std::move(message)});
  }

  void header() {
    p_.source = file_;
    if (d_.grafcet) {
      p_.name = d_.grafcet->name;
      p_.title = d_.grafcet->description;
    } else {
      std::string stem = file_;
      if (const auto slash = stem.find_last_of('/'); slash != std::string::npos)
        stem = stem.substr(slash + 1);
      if (const auto dot = stem.find('.'); dot != std::string::npos && dot > 0)
        stem = stem.substr(0, dot);
      p_.name = stem;
    }
    for (SourceLocation w : d_.extra_grafcet)
      error(w, "a second 'grafcet' statement: the name is given once, first declared at " +
                   at(d_.grafcet->where));
  }

  bool check_name(const detail::NameDecl& n, const char* what) {
    if (detail::is_reserved_name(n.name)) {
      error(n.where, std::string("'") + n.name + "' cannot name " + what +
                         ": keywords and X<number> (step variables) are reserved");
      return false;
    }
    return true;
  }

  void inputs() {
    bool limit_reported = false;
    for (const detail::NameDecl& n : d_.inputs) {
      if (!check_name(n, "an input")) continue;
      if (auto it = input_at_.find(n.name); it != input_at_.end()) {
        error(n.where, "input '" + n.name + "' is already declared at " + at(it->second));
        continue;
      }
      input_at_[n.name] = n.where;
      if (p_.inputs.size() == kMaxInputs) {
        if (!limit_reported)
          error(n.where, "too many inputs: at most " + std::to_string(kMaxInputs) + " per Grafcet");
        limit_reported = true;
        continue;
      }
      p_.inputs.push_back({n.name, n.description, n.where});
    }
  }

  // Declared actions first, then the others in order of first use.
  void actions() {
    for (const detail::NameDecl& n : d_.actions) {
      if (!check_name(n, "an action")) continue;
      if (int i = action_index(n.name); i >= 0) {
        error(n.where, "action '" + n.name + "' is already declared at " +
                           at(p_.actions[static_cast<std::size_t>(i)].where));
        continue;
      }
      add_action(n.name, n.description, n.where);
    }
    for (const detail::StepDraft& s : d_.steps)
      for (const detail::ActionRef& a : s.actions) {
        if (action_index(a.name) >= 0 || rejected_actions_.count(a.name) != 0) continue;
        if (!check_name({a.name, "", a.where}, "an action")) {
          rejected_actions_.insert(a.name);
          continue;
        }
        add_action(a.name, "", a.where);
      }
  }

  void add_action(const std::string& name, const std::string& description, SourceLocation w) {
    if (auto it = input_at_.find(name); it != input_at_.end()) {
      error(w, "'" + name + "' is an input (declared at " + at(it->second) +
                   "); an action needs another name");
      rejected_actions_.insert(name);
      return;
    }
    if (p_.actions.size() == kMaxActions) {
      if (!action_limit_reported_)
        error(w, "too many actions: at most " + std::to_string(kMaxActions) + " per Grafcet");
      action_limit_reported_ = true;
      rejected_actions_.insert(name);
      return;
    }
    p_.actions.push_back({name, description, w});
  }

  int action_index(const std::string& name) const {
    for (std::size_t i = 0; i < p_.actions.size(); ++i)
      if (p_.actions[i].name == name) return static_cast<int>(i);
    return -1;
  }

  void steps() {
    bool limit_reported = false;
    for (const detail::StepDraft& s : d_.steps) {
      const auto number = static_cast<std::uint32_t>(s.id.number);
      if (auto it = step_index_.find(number); it != step_index_.end()) {
        error(s.id.where, "step " + std::to_string(number) + " is already declared at " +
                              at(step_where_[number]));
        continue;
      }
      step_where_[number] = s.id.where;
      if (p_.steps.size() == kMaxSteps) {
        if (!limit_reported)
          error(s.id.where,
                "too many steps: at most " + std::to_string(kMaxSteps) + " per Grafcet");
        limit_reported = true;
        step_index_[number] = -1;
        continue;
      }
      step_index_[number] = static_cast<int>(p_.steps.size());
      Step step;
      step.number = number;
      step.label = s.label;
      step.initial = s.initial;
      step.where = s.id.where;
      for (const detail::ActionRef& a : s.actions) {
        const int i = action_index(a.name);
        if (i < 0) continue;  // already reported
        const Mask bit = Mask{1} << i;
        Mask& mask = a.impulse ? step.impulse_actions : step.level_actions;
        if ((mask & bit) != 0)
          error(a.where, "action '" + a.name + (a.impulse ? "*" : "") +
                             "' is listed twice for step " + std::to_string(number));
        mask |= bit;
      }
      p_.steps.push_back(std::move(step));
    }
    const bool any_broken = d_.step_statement_failed ||
                            std::any_of(d_.steps.begin(), d_.steps.end(),
                                        [](const detail::StepDraft& s) { return s.broken; });
    if (any_broken) return;  // what is missing may be in the broken statement
    if (d_.steps.empty()) {
      error({1, 1}, "the Grafcet has no step: declare steps with 'step <number> ...'");
    } else if (std::none_of(d_.steps.begin(), d_.steps.end(),
                            [](const detail::StepDraft& s) { return s.initial; })) {
      error(d_.steps.front().id.where, "no initial step: mark at least one, e.g. 'step " +
                                           std::to_string(d_.steps.front().id.number) +
                                           " initial'");
    }
  }

  // -1: unknown (reported here), -2: known but unusable (already reported).
  int step_ref(const detail::NumberRef& r) {
    const auto number = static_cast<std::uint32_t>(r.number);
    auto it = step_index_.find(number);
    if (it != step_index_.end()) return it->second < 0 ? -2 : it->second;
    if (broken_step(number)) return -2;
    error(r.where, "no step " + std::to_string(number) + " is declared");
    return -1;
  }
  bool broken_step(std::uint32_t number) const {
    return std::any_of(d_.steps.begin(), d_.steps.end(), [&](const detail::StepDraft& s) {
      return s.broken && s.id.number == number;
    });
  }

  Mask step_mask(const std::vector<detail::NumberRef>& refs, const char* what) {
    Mask m = 0;
    for (const detail::NumberRef& r : refs) {
      const int i = step_ref(r);
      if (i < 0) continue;
      const Mask bit = Mask{1} << i;
      if ((m & bit) != 0)
        error(r.where, "step " + std::to_string(r.number) + " is listed twice among the " + what);
      m |= bit;
    }
    return m;
  }

  void transitions() {
    for (const detail::TransitionDraft& t : d_.transitions) {
      const auto number = static_cast<std::uint32_t>(t.id.number);
      if (auto it = transition_where_.find(number); it != transition_where_.end()) {
        error(t.id.where, "transition (" + std::to_string(number) + ") is already declared at " +
                              at(it->second));
        continue;
      }
      transition_where_[number] = t.id.where;
      if (t.broken) continue;
      Transition out;
      out.number = number;
      out.where = t.id.where;
      out.preceding = step_mask(t.preceding, "preceding steps");
      out.following = step_mask(t.following, "following steps");
      compile(t.receptivity, Scope::kReceptivity, out.receptivity);
      transition_index_[number] = static_cast<int>(p_.transitions.size());
      p_.transitions.push_back(std::move(out));
    }
  }

  void orders() {
    const bool any_broken_transition =
        std::any_of(d_.transitions.begin(), d_.transitions.end(),
                    [](const detail::TransitionDraft& t) { return t.broken; });
    std::map<int, SourceLocation> ordered;
    for (const detail::OrderDraft& o : d_.orders) {
      const int s = step_ref(o.step);
      if (s < 0) continue;
      if (auto it = ordered.find(s); it != ordered.end()) {
        error(o.step.where, "step " + std::to_string(o.step.number) +
                                " already has a checking order, at " + at(it->second));
        continue;
      }
      ordered[s] = o.where;
      const Mask bit = Mask{1} << s;
      CheckingOrder out;
      out.step = static_cast<std::size_t>(s);
      out.where = o.where;
      bool ok = !o.broken;
      for (const detail::NumberRef& r : o.transitions) {
        const auto number = static_cast<std::uint32_t>(r.number);
        auto it = transition_index_.find(number);
        if (it == transition_index_.end()) {
          ok = false;
          if (transition_where_.count(number) == 0)
            error(r.where, "no transition (" + std::to_string(number) + ") is declared");
          continue;
        }
        const auto ti = static_cast<std::size_t>(it->second);
        if ((p_.transitions[ti].preceding & bit) == 0) {
          error(r.where, "transition (" + std::to_string(number) + ") does not leave step " +
                             std::to_string(o.step.number));
          ok = false;
          continue;
        }
        if (std::find(out.transitions.begin(), out.transitions.end(), ti) !=
            out.transitions.end()) {
          error(r.where, "transition (" + std::to_string(number) + ") is listed twice");
          ok = false;
          continue;
        }
        out.transitions.push_back(ti);
      }
      if (!ok || any_broken_transition) continue;
      for (std::size_t ti = 0; ti < p_.transitions.size(); ++ti) {
        if ((p_.transitions[ti].preceding & bit) == 0) continue;
        if (std::find(out.transitions.begin(), out.transitions.end(), ti) == out.transitions.end())
          error(o.where, "the order for step " + std::to_string(o.step.number) +
                             " must list every transition leaving it; (" +
                             std::to_string(p_.transitions[ti].number) + ") is missing");
      }
      p_.orders.push_back(std::move(out));
    }
  }

  void invariants() {
    std::map<std::string, SourceLocation> names;
    for (const detail::InvariantDraft& inv : d_.invariants) {
      if (auto it = names.find(inv.name); it != names.end())
        error(inv.where, "invariant \"" + inv.name + "\" is already declared at " + at(it->second));
      names.emplace(inv.name, inv.where);
      if (inv.broken) continue;
      Invariant out;
      out.name = inv.name;
      out.where = inv.where;
      compile(inv.condition, inv.next ? Scope::kCondition : Scope::kConclusion, out.condition);
      if (inv.next) {
        out.next.emplace();
        compile(*inv.next, Scope::kConclusion, *out.next);
      }
      p_.invariants.push_back(std::move(out));
    }
  }

  // ---- expressions --------------------------------------------------------
  void compile(const Ast& ast, Scope scope, Expression& out) {
    out.text = ast.text;
    out.where = ast.where;
    if (ast.root < 0) return;
    const std::size_t errors_before = errors_.size();
    const int depth = emit(ast, ast.root, scope, out);
    if (errors_.size() == errors_before && depth > 64)
      error(ast.where, "expression too deeply nested: it needs " + std::to_string(depth) +
                           " operand stack entries, at most 64");
  }

  void load(Expression& out, Operand operand, int index) {
    const auto bit = static_cast<std::uint8_t>(index);
    out.code.push_back({Instruction::Op::kLoad, operand, bit});
    out.reads[static_cast<std::uint8_t>(operand)] |= Mask{1} << bit;
  }

  // Emits postfix code; returns the operand stack depth the node needs.
  int emit(const Ast& ast, int index, Scope scope, Expression& out) {
    const Node& n = ast.nodes[static_cast<std::size_t>(index)];
    using K = Node::Kind;
    using Op = Instruction::Op;
    switch (n.kind) {
      case K::kConst:
        out.code.push_back({n.value ? Op::kTrue : Op::kFalse, Operand::kInput, 0});
        return 1;
      case K::kName:
        name(n, scope, out);
        return 1;
      case K::kImpulse:
        impulse(n, scope, out);
        return 1;
      case K::kRise:
      case K::kFall: {
        const int i = find_input(n.name);
        if (i < 0)
          error(n.where,
                "edges apply to declared inputs; '" + std::string(n.name) + "' is not one");
        else
          load(out, n.kind == K::kRise ? Operand::kRise : Operand::kFall, i);
        return 1;
      }
      case K::kNot: {
        const int d = emit(ast, n.a, scope, out);
        out.code.push_back({Op::kNot, Operand::kInput, 0});
        return d;
      }
      case K::kAnd:
      case K::kOr:
      case K::kImplies:
      case K::kEquiv: {
        const int da = emit(ast, n.a, scope, out);
        const int db = emit(ast, n.b, scope, out);
        const Op op = n.kind == K::kAnd       ? Op::kAnd
                      : n.kind == K::kOr      ? Op::kOr
                      : n.kind == K::kImplies ? Op::kImplies
                                              : Op::kEquiv;
        out.code.push_back({op, Operand::kInput, 0});
        return std::max(da, db + 1);
      }
    }
    return 1;
  }

  int find_input(std::string_view name) const {
    for (std::size_t i = 0; i < p_.inputs.size(); ++i)
      if (p_.inputs[i].name == name) return static_cast<int>(i);
    return -1;
  }

  void name(const Node& n, Scope scope, Expression& out) {
    const std::string name(n.name);
    if (const int i = find_input(name); i >= 0) return load(out, Operand::kInput, i);
    if (detail::is_reserved_name(name) && name[0] == 'X') {
      const std::string digits = name.substr(1);
      if (digits.size() > 9) {
        error(n.where, "no step " + digits + " is declared");
        return;
      }
      const detail::NumberRef r{std::stoull(digits), n.where};
      const int s = step_ref(r);
      if (s >= 0) load(out, Operand::kStep, s);
      return;
    }
    if (const int a = action_index(name); a >= 0) {
      if (scope == Scope::kReceptivity)
        error(n.where, "'" + name +
                           "' is an action; a receptivity reads inputs, their edges "
                           "(↑a, ↓a) and step variables (X1, ...)");
      else
        load(out, Operand::kLevelAction, a);
      return;
    }
    if (input_at_.count(name) != 0 || rejected_actions_.count(name) != 0) return;
    error(n.where, "unknown name '" + name + "': not a declared input" +
                       (scope == Scope::kReceptivity ? std::string() : std::string(", an action")) +
                       " or a step variable X<number>");
  }

  void impulse(const Node& n, Scope scope, Expression& out) {
    const std::string name(n.name);
    const int a = action_index(name);
    if (a < 0) {
      if (rejected_actions_.count(name) == 0)
        error(n.where, "unknown action '" + name + "' in '" + name + "*'");
      return;
    }
    if (scope == Scope::kReceptivity) {
      error(n.where, "'" + name + "*' is an impulse action; receptivities cannot read actions");
      return;
    }
    if (scope == Scope::kCondition) {
      error(n.where, "'" + name +
                         "*' (impulse fired) can be read after 'next' or in an "
                         "invariant without 'next', not in the condition before it");
      return;
    }
    load(out, Operand::kImpulseAction, a);
  }

  const detail::Draft& d_;
  std::string file_;
  std::vector<Diagnostic>& errors_;
  Grafcet::Parts p_;
  std::map<std::string, SourceLocation> input_at_;
  std::set<std::string> rejected_actions_;
  bool action_limit_reported_ = false;
  std::map<std::uint32_t, int> step_index_;
  std::map<std::uint32_t, SourceLocation> step_where_;
  std::map<std::uint32_t, int> transition_index_;
  std::map<std::uint32_t, SourceLocation> transition_where_;
};

ParseResult parse(std::string_view text, std::string_view file) {
  ParseResult result;
  std::vector<detail::LexError> syntax;
  const std::vector<detail::Token> tokens = detail::lex(text, syntax);
  const detail::Draft draft = detail::parse_draft(tokens, syntax);
  for (detail::LexError& e : syntax)
    result.errors.push_back({std::string(file), e.where, std::move(e.message)});
  std::optional<Grafcet> g = GrafcetBuilder(draft, std::string(file), result.errors).build();
  std::stable_sort(
      result.errors.begin(), result.errors.end(), [](const Diagnostic& a, const Diagnostic& b) {
        return a.location.line != b.location.line ? a.location.line < b.location.line
                                                  : a.location.column < b.location.column;
      });
  if (result.errors.size() > kMaxErrors) {
    const std::size_t more = result.errors.size() - kMaxErrors;
    result.errors.erase(result.errors.begin() + static_cast<std::ptrdiff_t>(kMaxErrors),
                        result.errors.end());
    result.errors.push_back(
        {std::string(file), SourceLocation{}, "and " + std::to_string(more) + " more errors"});
  }
  if (result.errors.empty()) result.grafcet = std::move(g);
  return result;
}

ParseResult parse_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    ParseResult r;
    r.errors.push_back({path, {}, "cannot open the file"});
    return r;
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    ParseResult r;
    r.errors.push_back({path, {}, "cannot read the file"});
    return r;
  }
  return parse(text.str(), path);
}

}  // namespace smc::grafcet
