// Syntax of the Grafcet text format (README.md): tokens -> Draft. Every
// statement is one line (a trailing '\' continues it); a syntax error is
// recorded and parsing resumes on the next line.

#include <algorithm>
#include <limits>
#include <utility>

#include "parser_internal.hpp"

namespace smc::grafcet::detail {
namespace {

struct SyntaxError {
  SourceLocation where;
  std::string message;
};

constexpr std::string_view kKeywords[] = {"grafcet",   "input",      "action", "step",
                                          "initial",   "transition", "when",   "order",
                                          "invariant", "next",       "rise",   "fall"};

class Parser {
 public:
  Parser(const std::vector<Token>& tokens, std::vector<LexError>& errors)
      : t_(tokens), errors_(errors) {}

  Draft run() {
    while (!at(Tok::kEof)) {
      try {
        statement();
      } catch (const SyntaxError& e) {
        errors_.push_back({e.where, e.message});
        while (!at(Tok::kNewline) && !at(Tok::kEof)) ++i_;
      }
      if (at(Tok::kNewline)) ++i_;
    }
    return std::move(d_);
  }

 private:
  // ---- tokens -------------------------------------------------------------
  const Token& peek(std::size_t k = 0) const { return i_ + k < t_.size() ? t_[i_ + k] : t_.back(); }
  bool at(Tok k) const { return peek().kind == k; }
  bool at_word(std::string_view w, std::size_t k = 0) const {
    return peek(k).kind == Tok::kIdent && peek(k).text == w;
  }
  const Token& take() {
    const Token& t = peek();
    if (i_ < t_.size() - 1) ++i_;
    return t;
  }
  [[noreturn]] void fail(const std::string& expected) const {
    throw SyntaxError{peek().where, "expected " + expected + ", found " + describe(peek())};
  }
  const Token& expect(Tok k, const std::string& what) {
    if (!at(k)) fail(what);
    return take();
  }
  static bool is_keyword(std::string_view w) {
    for (std::string_view k : kKeywords)
      if (k == w) return true;
    return false;
  }

  NumberRef number(const std::string& what, bool allow_parens = false) {
    const bool paren = allow_parens && at(Tok::kLParen);
    if (paren) take();
    const Token& t = expect(Tok::kNumber, what);
    if (t.number > std::numeric_limits<std::uint32_t>::max())
      throw SyntaxError{t.where, "number " + std::string(t.text) + " is too large (at most " +
                                     std::to_string(std::numeric_limits<std::uint32_t>::max()) +
                                     ")"};
    if (paren) expect(Tok::kRParen, "')' after " + what);
    return {t.number, t.where};
  }

  std::string name(const std::string& what) {
    if (at(Tok::kIdent) && is_keyword(peek().text))
      throw SyntaxError{peek().where, "expected " + what + ", found the keyword '" +
                                          std::string(peek().text) + "'"};
    return std::string(expect(Tok::kIdent, what).text);
  }

  void end_of_statement(const char* after) {
    if (!at(Tok::kNewline) && !at(Tok::kEof)) fail(std::string("end of line after ") + after);
  }

  // ---- statements ---------------------------------------------------------
  void statement() {
    if (at(Tok::kNewline)) return;
    if (at_word("grafcet")) return grafcet_statement();
    if (at_word("input")) return name_list(d_.inputs, "an input name");
    if (at_word("action")) return name_list(d_.actions, "an action name");
    if (at_word("step")) return step_statement();
    if (at_word("transition")) return transition_statement();
    if (at_word("order")) return order_statement();
    if (at_word("invariant")) return invariant_statement();
    fail("a statement (grafcet, input, action, step, transition, order or invariant)");
  }

  void grafcet_statement() {
    const Token& kw = take();
    NameDecl g;
    g.where = kw.where;
    g.name = name("the Grafcet's name after 'grafcet'");
    if (at(Tok::kString)) g.description = take().value;
    end_of_statement("the Grafcet's name and title");
    if (d_.grafcet)
      d_.extra_grafcet.push_back(kw.where);
    else
      d_.grafcet = std::move(g);
  }

  void name_list(std::vector<NameDecl>& list, const std::string& what) {
    const std::string kw(take().text);
    for (;;) {
      NameDecl n;
      n.where = peek().where;
      n.name = name(what + " after '" + kw + "'");
      if (at(Tok::kString)) n.description = take().value;
      list.push_back(std::move(n));
      if (!at(Tok::kComma)) break;
      take();
    }
    end_of_statement("the declaration (separate several names with ',')");
  }

  void step_statement() {
    take();
    const bool failed_before = d_.step_statement_failed;
    d_.step_statement_failed = true;  // stays set if the number does not parse
    const NumberRef id = number("a step number after 'step'");
    d_.step_statement_failed = failed_before;
    d_.steps.push_back(StepDraft{.id = id, .broken = true});
    StepDraft& s = d_.steps.back();
    if (at_word("initial")) {
      take();
      s.initial = true;
    }
    if (at(Tok::kString)) s.label = take().value;
    if (at(Tok::kColon)) {
      take();
      for (;;) {
        ActionRef a;
        a.where = peek().where;
        a.name = name("an action name (e.g. A, or L* for an impulse action)");
        if (at(Tok::kStar)) {
          take();
          a.impulse = true;
        }
        s.actions.push_back(std::move(a));
        if (at(Tok::kComma)) {
          take();
          continue;
        }
        if (at(Tok::kIdent)) continue;
        break;
      }
      end_of_statement("the step's actions");
    } else if (s.label.empty() && !s.initial) {
      if (!at(Tok::kNewline) && !at(Tok::kEof))
        fail("'initial', a label string, ':' before the actions, or end of line");
    } else {
      end_of_statement(s.label.empty() ? "'initial' (actions follow a ':')"
                                       : "the step's label (actions follow a ':')");
    }
    s.broken = false;
  }

  std::vector<NumberRef> step_list(const std::string& what) {
    std::vector<NumberRef> out;
    out.push_back(number(what));
    while (at(Tok::kComma)) {
      take();
      out.push_back(number("a step number after ','"));
    }
    return out;
  }

  void transition_statement() {
    take();
    const NumberRef id = number("a transition number after 'transition'", true);
    d_.transitions.push_back(TransitionDraft{.id = id, .broken = true});
    TransitionDraft& t = d_.transitions.back();
    expect(Tok::kColon, "':' after the transition number");
    t.preceding = step_list("the preceding step numbers (e.g. '4 -> 2')");
    expect(Tok::kArrow, "'->' between preceding and following steps");
    t.following = step_list("the following step numbers after '->'");
    if (!at_word("when")) fail("'when' and the receptivity after the following steps");
    take();
    t.receptivity = expression("a receptivity after 'when'", nullptr);
    end_of_statement("the receptivity");
    t.broken = false;
  }

  void order_statement() {
    const Token& kw = take();
    OrderDraft o;
    o.where = kw.where;
    o.step = number("a step number after 'order'");
    d_.orders.push_back(std::move(o));
    OrderDraft& ref = d_.orders.back();
    ref.broken = true;
    expect(Tok::kColon, "':' after the step number (order 4: 5, 7, 6)");
    ref.transitions.push_back(number("a transition number", true));
    while (at(Tok::kComma)) {
      take();
      ref.transitions.push_back(number("a transition number after ','", true));
    }
    end_of_statement("the checking order");
    ref.broken = false;
  }

  void invariant_statement() {
    const Token& kw = take();
    InvariantDraft inv;
    inv.where = kw.where;
    inv.name = expect(Tok::kString, "the invariant's name as a string after 'invariant'").value;
    d_.invariants.push_back(std::move(inv));
    InvariantDraft& ref = d_.invariants.back();
    ref.broken = true;
    expect(Tok::kColon, "':' after the invariant's name");
    std::optional<Ast> next;
    ref.condition = expression("the invariant's expression", &next);
    ref.next = std::move(next);
    end_of_statement("the invariant");
    ref.broken = false;
  }

  // ---- expressions --------------------------------------------------------
  // `next` non-null: an invariant, which may take the form
  // CONDITION -> next CONCLUSION (the conclusion goes to *next).
  Ast expression(const std::string& what, std::optional<Ast>* next) {
    Ast ast;
    ast_ = &ast;
    const std::size_t first = i_;
    if (!starts_operand()) fail(what);
    ast.where = peek().where;
    if (next == nullptr) {
      ast.root = implication();
    } else {
      const int lhs = equivalence();
      if (at(Tok::kArrow) && at_word("next", 1)) {
        ast.root = lhs;
        ast.text = text(first, i_);
        take();
        take();
        Ast conclusion;
        ast_ = &conclusion;
        const std::size_t c_first = i_;
        if (!starts_operand()) fail("the conclusion after 'next'");
        conclusion.where = peek().where;
        conclusion.root = implication();
        conclusion.text = text(c_first, i_);
        *next = std::move(conclusion);
        ast_ = nullptr;
        return ast;
      }
      if (at(Tok::kArrow)) {
        const Token& op = take();
        const int rhs = implication();
        ast.root = add({.kind = Node::Kind::kImplies, .where = op.where, .a = lhs, .b = rhs});
      } else {
        ast.root = lhs;
      }
    }
    ast.text = text(first, i_);
    ast_ = nullptr;
    return ast;
  }

  std::string text(std::size_t from, std::size_t to) const {
    std::string s;
    for (std::size_t k = from; k < to; ++k) {
      if (k > from && t_[k].begin > t_[k - 1].end) s += ' ';
      s += t_[k].text;
    }
    return s;
  }

  // Bounds that keep every recursive walk of an expression (this parser,
  // the checks, the compiler, the printer) well inside the stack, whatever
  // the text: parentheses, '!' and '->' nested at most kMaxNesting deep, and
  // a tree at most kMaxDepth operators deep (a chain "a & b & ..." is one
  // level per '&').
  static constexpr int kMaxNesting = 100;
  static constexpr int kMaxDepth = 500;

  int add(Node n) {
    for (const int child : {n.a, n.b}) {
      if (child >= 0)
        n.depth = std::max(n.depth, ast_->nodes[static_cast<std::size_t>(child)].depth + 1);
    }
    if (n.depth > kMaxDepth) {
      throw SyntaxError{n.where, "expression more than " + std::to_string(kMaxDepth) +
                                     " operators deep; split it (e.g. into named conditions)"};
    }
    ast_->nodes.push_back(n);
    return static_cast<int>(ast_->nodes.size() - 1);
  }

  // One more level of nesting for the parser's own recursion.
  class Nest {
   public:
    Nest(Parser& p, SourceLocation where) : p_(p) {
      if (++p_.nesting_ > kMaxNesting) {
        --p_.nesting_;
        throw SyntaxError{where, "expression nested more than " + std::to_string(kMaxNesting) +
                                     " levels deep (parentheses, '!', '->'); split it"};
      }
    }
    ~Nest() { --p_.nesting_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;

   private:
    Parser& p_;
  };

  bool starts_operand() const {
    switch (peek().kind) {
      case Tok::kNumber:
      case Tok::kLParen:
      case Tok::kNot:
      case Tok::kRise:
      case Tok::kFall:
        return true;
      case Tok::kIdent:
        return peek().text != "next" &&
               (!is_keyword(peek().text) || peek().text == "rise" || peek().text == "fall");
      default:
        return false;
    }
  }

  int implication() {
    const int lhs = equivalence();
    if (!at(Tok::kArrow)) return lhs;
    if (at_word("next", 1))
      throw SyntaxError{peek(1).where,
                        "'next' is allowed only in an invariant, as CONDITION -> next "
                        "CONCLUSION at its top level"};
    const Token& op = take();
    const Nest nest(*this, op.where);
    const int rhs = implication();
    return add({.kind = Node::Kind::kImplies, .where = op.where, .a = lhs, .b = rhs});
  }

  int equivalence() {
    int lhs = disjunction();
    while (at(Tok::kEquiv)) {
      const Token& op = take();
      const int rhs = disjunction();
      lhs = add({.kind = Node::Kind::kEquiv, .where = op.where, .a = lhs, .b = rhs});
    }
    return lhs;
  }

  int disjunction() {
    int lhs = conjunction();
    while (at(Tok::kOr)) {
      const Token& op = take();
      const int rhs = conjunction();
      lhs = add({.kind = Node::Kind::kOr, .where = op.where, .a = lhs, .b = rhs});
    }
    return lhs;
  }

  int conjunction() {
    int lhs = unary();
    for (;;) {
      SourceLocation where = peek().where;
      if (at(Tok::kAnd)) {
        take();
      } else if (!starts_operand()) {
        break;  // juxtaposition "a b" is a conjunction too
      }
      const int rhs = unary();
      lhs = add({.kind = Node::Kind::kAnd, .where = where, .a = lhs, .b = rhs});
    }
    return lhs;
  }

  int unary() {
    if (at(Tok::kNot)) {
      const Token& op = take();
      const Nest nest(*this, op.where);
      const int a = unary();
      return add({.kind = Node::Kind::kNot, .where = op.where, .a = a});
    }
    int p = primary();
    while (at(Tok::kPrime)) {
      const Token& op = take();
      p = add({.kind = Node::Kind::kNot, .where = op.where, .a = p});
    }
    return p;
  }

  int edge(Node::Kind kind, SourceLocation where, bool parens) {
    if (parens) expect(Tok::kLParen, "'(' after 'rise' or 'fall'");
    if (!at(Tok::kIdent) || is_keyword(peek().text)) fail("an input name for the edge");
    const Token& n = take();
    if (parens) expect(Tok::kRParen, "')' after the input name");
    return add({.kind = kind, .name = n.text, .where = where});
  }

  int primary() {
    const Token& t = peek();
    switch (t.kind) {
      case Tok::kNumber:
        if (t.text != "0" && t.text != "1")
          throw SyntaxError{t.where,
                            "expected the constant 0 or 1, found number " + std::string(t.text)};
        take();
        return add({.kind = Node::Kind::kConst, .value = t.text == "1", .where = t.where});
      case Tok::kRise:
      case Tok::kFall:
        take();
        return edge(t.kind == Tok::kRise ? Node::Kind::kRise : Node::Kind::kFall, t.where,
                    at(Tok::kLParen));
      case Tok::kLParen: {
        take();
        const Nest nest(*this, t.where);
        const int inner = implication();
        if (!at(Tok::kRParen))
          fail("')' to close the '(' at " + std::to_string(t.where.line) + ":" +
               std::to_string(t.where.column));
        take();
        return inner;
      }
      case Tok::kIdent:
        if (t.text == "rise" || t.text == "fall") {
          take();
          return edge(t.text == "rise" ? Node::Kind::kRise : Node::Kind::kFall, t.where, true);
        }
        if (t.text == "next")
          throw SyntaxError{t.where,
                            "'next' is allowed only in an invariant, as CONDITION -> next "
                            "CONCLUSION at its top level"};
        if (is_keyword(t.text)) fail("an operand");
        take();
        if (at(Tok::kStar)) {
          take();
          return add({.kind = Node::Kind::kImpulse, .name = t.text, .where = t.where});
        }
        return add({.kind = Node::Kind::kName, .name = t.text, .where = t.where});
      default:
        fail(
            "an operand (an input, a step variable such as X4, 0, 1, '!', '(' or an edge "
            "such as ↑a)");
    }
  }

  const std::vector<Token>& t_;
  std::vector<LexError>& errors_;
  std::size_t i_ = 0;
  int nesting_ = 0;
  Draft d_;
  Ast* ast_ = nullptr;
};

}  // namespace

bool is_reserved_name(std::string_view name) {
  for (std::string_view k : kKeywords)
    if (k == name) return true;
  if (name.size() >= 2 && name[0] == 'X') {
    for (std::size_t k = 1; k < name.size(); ++k)
      if (name[k] < '0' || name[k] > '9') return false;
    return true;
  }
  return false;
}

Draft parse_draft(const std::vector<Token>& tokens, std::vector<LexError>& errors) {
  return Parser(tokens, errors).run();
}

}  // namespace smc::grafcet::detail
