#include "auth.hpp"

#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace smc::dashboard {

namespace {

bool valid_name(std::string_view s) {
  if (s.empty() || s.size() > Auth::kMaxNameLength) return false;
  for (const char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-' || c == '@';
    if (!ok) return false;
  }
  return true;
}

bool valid_token(std::string_view s) {
  for (const char c : s) {
    if (c <= ' ' || c > '~') return false;
  }
  return s.size() >= Auth::kMinTokenLength;
}

// Equal-length comparison whose time does not depend on where they differ.
bool same(std::string_view a, std::string_view b) {
  unsigned diff = a.size() == b.size() ? 0U : 1U;
  for (size_t i = 0; i < b.size(); ++i) {
    const char x = i < a.size() ? a[i] : '\0';
    diff |= static_cast<unsigned>(static_cast<unsigned char>(x) ^ static_cast<unsigned char>(b[i]));
  }
  return diff == 0;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

}  // namespace

Auth Auth::parse(std::string_view text, std::string_view source) {
  Auth auth;
  std::string errors;
  size_t line_no = 0;
  while (!text.empty()) {
    ++line_no;
    const size_t eol = text.find('\n');
    std::string_view line = trim(text.substr(0, eol));
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    if (line.empty() || line.front() == '#') continue;
    const std::string where = std::string(source) + ":" + std::to_string(line_no) + ": ";
    const size_t sp = line.find_first_of(" \t");
    if (sp == std::string_view::npos) {
      errors += where + "expected 'NAME TOKEN', found one word\n";
      continue;
    }
    const std::string_view name = line.substr(0, sp);
    const std::string_view token = trim(line.substr(sp));
    if (!valid_name(name)) {
      errors += where + "operator name '" + std::string(name) +
                "' must be 1-31 characters of A-Z a-z 0-9 . _ - @\n";
      continue;
    }
    if (!valid_token(token)) {
      errors += where + "token of '" + std::string(name) + "' must be at least " +
                std::to_string(kMinTokenLength) + " printable characters without spaces\n";
      continue;
    }
    bool duplicate = false;
    for (const auto& op : auth.operators_) {
      if (op.name == name) errors += where + "operator '" + std::string(name) + "' listed twice\n";
      if (op.token == token)
        errors +=
            where + "token of '" + std::string(name) + "' is also the token of '" + op.name + "'\n";
      duplicate = duplicate || op.name == name || op.token == token;
    }
    if (!duplicate) auth.operators_.push_back({std::string(name), std::string(token)});
  }
  if (!errors.empty()) {
    errors.pop_back();
    throw std::runtime_error(errors);
  }
  return auth;
}

Auth Auth::from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the operator token file");
  std::ostringstream ss;
  ss << in.rdbuf();
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && (st.st_mode & 077) != 0) {
    spdlog::warn("{}: operator token file is readable by group or others (chmod 600)", path);
  }
  return parse(ss.str(), path);
}

std::optional<std::string> Auth::authenticate(std::string_view authorization) const {
  constexpr std::string_view kBearer = "Bearer ";
  if (authorization.size() <= kBearer.size()) return std::nullopt;
  for (size_t i = 0; i < kBearer.size(); ++i) {  // the scheme is case-insensitive
    const char c = authorization[i];
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    const char want = kBearer[i];
    const char want_lower =
        (want >= 'A' && want <= 'Z') ? static_cast<char>(want - 'A' + 'a') : want;
    if (lower != want_lower) return std::nullopt;
  }
  const std::string_view token = trim(authorization.substr(kBearer.size()));
  const Operator* found = nullptr;
  for (const auto& op : operators_) {  // no early exit: same time for every token
    if (same(token, op.token) && found == nullptr) found = &op;
  }
  if (found == nullptr) return std::nullopt;
  return found->name;
}

}  // namespace smc::dashboard
