#pragma once
// Internal: tokens of the Grafcet text format.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "smc/grafcet/model.hpp"

namespace smc::grafcet::detail {

enum class Tok : std::uint8_t {
  kIdent,
  kNumber,
  kString,
  kNewline,
  kEof,
  kColon,
  kComma,
  kArrow,  // -> or →
  kEquiv,  // <-> or ↔
  kLParen,
  kRParen,
  kNot,    // ! ~ ¬
  kPrime,  // ' ’ (postfix complement)
  kAnd,    // & && · ∧
  kOr,     // + | || ∨
  kStar,   // * (impulse action)
  kRise,   // ↑
  kFall,   // ↓
};

struct Token {
  Tok kind = Tok::kEof;
  std::string_view text;  // the source bytes
  SourceLocation where;
  std::size_t begin = 0;  // byte offsets in the source
  std::size_t end = 0;
  std::uint64_t number = 0;  // kNumber; UINT64_MAX when too large
  std::string value;         // kString, unescaped
};

struct LexError {
  SourceLocation where;
  std::string message;
};

// Tokenizes the whole text; always ends with kNewline then kEof.
std::vector<Token> lex(std::string_view text, std::vector<LexError>& errors);

// "end of line", "name 'abc'", "'->'", ...
std::string describe(const Token& token);

}  // namespace smc::grafcet::detail
