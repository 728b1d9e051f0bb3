#pragma once
// Internal: the parser's stages. lex (lexer.hpp) -> parse_draft -> build
// (builder.cpp, class GrafcetBuilder).

#include <string_view>
#include <vector>

#include "draft.hpp"
#include "lexer.hpp"

namespace smc::grafcet::detail {

// Keywords and the step-variable names X<digits>.
bool is_reserved_name(std::string_view name);

// Syntax errors go to `errors`; the Draft holds what was read.
Draft parse_draft(const std::vector<Token>& tokens, std::vector<LexError>& errors);

}  // namespace smc::grafcet::detail
