#include "lexer.hpp"

#include <limits>

namespace smc::grafcet::detail {
namespace {

bool is_ident_start(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool is_ident_char(char c) { return is_ident_start(c) || (c >= '0' && c <= '9'); }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

class Lexer {
 public:
  Lexer(std::string_view text, std::vector<LexError>& errors) : s_(text), errors_(errors) {}

  std::vector<Token> run() {
    while (i_ < s_.size()) next();
    push(Tok::kNewline, i_, i_, here());
    push(Tok::kEof, i_, i_, here());
    return std::move(out_);
  }

 private:
  SourceLocation here() const { return {line_, col_}; }
  unsigned char byte(std::size_t k) const {
    return k < s_.size() ? static_cast<unsigned char>(s_[k]) : 0;
  }

  // Advances over n bytes on the current line, counting code points.
  void advance(std::size_t n) {
    for (std::size_t k = 0; k < n && i_ < s_.size(); ++k, ++i_)
      if ((byte(i_) & 0xC0u) != 0x80u) ++col_;
  }
  void newline() {
    ++i_;
    ++line_;
    col_ = 1;
  }

  Token& push(Tok kind, std::size_t begin, std::size_t end, SourceLocation where) {
    Token t;
    t.kind = kind;
    t.text = s_.substr(begin, end - begin);
    t.where = where;
    t.begin = begin;
    t.end = end;
    out_.push_back(std::move(t));
    return out_.back();
  }
  void simple(Tok kind, std::size_t n) {
    const SourceLocation w = here();
    const std::size_t b = i_;
    advance(n);
    push(kind, b, i_, w);
  }
  void error(SourceLocation where, std::string message) {
    errors_.push_back({where, std::move(message)});
  }

  // Length of the UTF-8 sequence starting at i_ (1 for a stray byte).
  std::size_t utf8_length() const {
    const unsigned char c = byte(i_);
    std::size_t n = 1;
    if ((c & 0xE0u) == 0xC0u)
      n = 2;
    else if ((c & 0xF0u) == 0xE0u)
      n = 3;
    else if ((c & 0xF8u) == 0xF0u)
      n = 4;
    for (std::size_t k = 1; k < n; ++k)
      if ((byte(i_ + k) & 0xC0u) != 0x80u) return 1;
    return n;
  }

  void next() {
    const char c = s_[i_];
    const SourceLocation w = here();
    if (c == ' ' || c == '\t' || c == '\r') {
      advance(1);
    } else if (c == '\n') {
      push(Tok::kNewline, i_, i_ + 1, w);
      newline();
    } else if (c == '#') {
      while (i_ < s_.size() && s_[i_] != '\n') advance(1);
    } else if (c == '\\') {
      std::size_t k = i_ + 1;
      while (k < s_.size() && (s_[k] == ' ' || s_[k] == '\t' || s_[k] == '\r')) ++k;
      if (k < s_.size() && s_[k] == '#')
        while (k < s_.size() && s_[k] != '\n') ++k;
      if (k >= s_.size() || s_[k] == '\n') {
        advance(k - i_);
        if (i_ < s_.size()) newline();
      } else {
        error(w, "stray '\\': a line continuation '\\' must end the line");
        advance(1);
      }
    } else if (is_digit(c)) {
      const std::size_t b = i_;
      std::uint64_t v = 0;
      bool overflow = false;
      while (i_ < s_.size() && is_digit(s_[i_])) {
        const auto d = static_cast<std::uint64_t>(s_[i_] - '0');
        if (v > (std::numeric_limits<std::uint64_t>::max() - d) / 10) overflow = true;
        v = v * 10 + d;
        advance(1);
      }
      push(Tok::kNumber, b, i_, w).number =
          overflow ? std::numeric_limits<std::uint64_t>::max() : v;
    } else if (is_ident_start(c)) {
      const std::size_t b = i_;
      while (i_ < s_.size() && is_ident_char(s_[i_])) advance(1);
      push(Tok::kIdent, b, i_, w);
    } else if (c == '"') {
      string_literal();
    } else if (c == ':') {
      simple(Tok::kColon, 1);
    } else if (c == ',') {
      simple(Tok::kComma, 1);
    } else if (c == '(') {
      simple(Tok::kLParen, 1);
    } else if (c == ')') {
      simple(Tok::kRParen, 1);
    } else if (c == '*') {
      simple(Tok::kStar, 1);
    } else if (c == '\'') {
      simple(Tok::kPrime, 1);
    } else if (c == '+') {
      simple(Tok::kOr, 1);
    } else if (c == '!' || c == '~') {
      simple(Tok::kNot, 1);
    } else if (c == '&') {
      simple(Tok::kAnd, byte(i_ + 1) == '&' ? 2 : 1);
    } else if (c == '|') {
      simple(Tok::kOr, byte(i_ + 1) == '|' ? 2 : 1);
    } else if (c == '-' && byte(i_ + 1) == '>') {
      simple(Tok::kArrow, 2);
    } else if (c == '<' && byte(i_ + 1) == '-' && byte(i_ + 2) == '>') {
      simple(Tok::kEquiv, 3);
    } else {
      unicode_or_error();
    }
  }

  void unicode_or_error() {
    const std::string_view rest = s_.substr(i_);
    struct Symbol {
      std::string_view utf8;
      Tok kind;
    };
    static constexpr Symbol kSymbols[] = {
        {"\xC2\xB7", Tok::kAnd},        // ·
        {"\xE2\x88\xA7", Tok::kAnd},    // ∧
        {"\xE2\x88\xA8", Tok::kOr},     // ∨
        {"\xC2\xAC", Tok::kNot},        // ¬
        {"\xE2\x80\x99", Tok::kPrime},  // ’
        {"\xE2\x86\x91", Tok::kRise},   // ↑
        {"\xE2\x86\x93", Tok::kFall},   // ↓
        {"\xE2\x86\x92", Tok::kArrow},  // →
        {"\xE2\x86\x94", Tok::kEquiv},  // ↔
    };
    for (const Symbol& sym : kSymbols) {
      if (rest.substr(0, sym.utf8.size()) == sym.utf8) {
        simple(sym.kind, sym.utf8.size());
        return;
      }
    }
    const SourceLocation w = here();
    const std::size_t n = utf8_length();
    const char c = s_[i_];
    std::string message = "unexpected character '";
    message.append(s_.substr(i_, n));
    message += '\'';
    if (c == '-' || c == '<' || c == '>') message += ": expected '->' or '<->'";
    if (c == '=') message += ": write '<->' for equivalence";
    error(w, std::move(message));
    advance(n);
  }

  void string_literal() {
    const SourceLocation w = here();
    const std::size_t b = i_;
    advance(1);
    std::string value;
    bool closed = false;
    while (i_ < s_.size() && s_[i_] != '\n') {
      const char c = s_[i_];
      if (c == '"') {
        advance(1);
        closed = true;
        break;
      }
      if (c == '\\' && (byte(i_ + 1) == '"' || byte(i_ + 1) == '\\')) {
        value += s_[i_ + 1];
        advance(2);
        continue;
      }
      value += c;
      advance(1);
    }
    if (!closed) error(w, "unterminated string: expected '\"' before the end of the line");
    push(Tok::kString, b, i_, w).value = std::move(value);
  }

  std::string_view s_;
  std::vector<LexError>& errors_;
  std::vector<Token> out_;
  std::size_t i_ = 0;
  std::uint32_t line_ = 1;
  std::uint32_t col_ = 1;
};

}  // namespace

std::vector<Token> lex(std::string_view text, std::vector<LexError>& errors) {
  return Lexer(text, errors).run();
}

std::string describe(const Token& t) {
  std::string out;
  switch (t.kind) {
    case Tok::kIdent:
      out = "name '";
      break;
    case Tok::kNumber:
      out = "number ";
      break;
    case Tok::kString:
      out = "string ";
      break;
    case Tok::kNewline:
      return "end of line";
    case Tok::kEof:
      return "end of file";
    default:
      out = "'";
      break;
  }
  out.append(t.text);
  if (t.kind != Tok::kNumber && t.kind != Tok::kString) out += '\'';
  return out;
}

}  // namespace smc::grafcet::detail
