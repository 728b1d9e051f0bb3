#include "auth.hpp"

#include <openssl/evp.h>
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

// A comparison whose time does not depend on where the digests differ.
template <class D>
bool same(const D& a, const D& b) {
  unsigned diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned>(a[i] ^ b[i]);
  return diff == 0;
}

constexpr std::string_view kSha256Prefix = "sha256:";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Starts with "sha256:", in any case: meant as a hash.
bool has_hash_prefix(std::string_view s) {
  if (s.size() < kSha256Prefix.size()) return false;
  for (size_t i = 0; i < kSha256Prefix.size(); ++i) {
    const char c = s[i];
    if ((c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c) != kSha256Prefix[i]) {
      return false;
    }
  }
  return true;
}

// "sha256:" and 64 hex digits; false for anything else.
template <class D>
bool parse_digest(std::string_view s, D& out) {
  if (s.size() != kSha256Prefix.size() + 2 * out.size() || !has_hash_prefix(s)) return false;
  s.remove_prefix(kSha256Prefix.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const int hi = hex_value(s[2 * i]);
    const int lo = hex_value(s[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<unsigned char>(hi * 16 + lo);
  }
  return true;
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
    Digest d{};
    const bool hashed = parse_digest(token, d);
    if (!hashed && has_hash_prefix(token)) {
      errors += where + "token hash of '" + std::string(name) +
                "' must be 'sha256:' and 64 hex digits (smc-dashboard --hash-token NAME)\n";
      continue;
    }
    if (!hashed && !valid_token(token)) {
      errors += where + "token of '" + std::string(name) + "' must be at least " +
                std::to_string(kMinTokenLength) + " printable characters without spaces\n";
      continue;
    }
    if (!hashed) d = digest(token);
    bool duplicate = false;
    for (const auto& op : auth.operators_) {
      if (op.name == name) errors += where + "operator '" + std::string(name) + "' listed twice\n";
      if (op.token_sha256 == d)
        errors +=
            where + "token of '" + std::string(name) + "' is also the token of '" + op.name + "'\n";
      duplicate = duplicate || op.name == name || op.token_sha256 == d;
    }
    if (duplicate) continue;
    auth.operators_.push_back({std::string(name), d});
    if (!hashed) auth.in_clear_.emplace_back(name);
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
  Auth auth = parse(ss.str(), path);
  for (const auto& name : auth.in_clear()) {
    spdlog::warn(
        "{}: the token of '{}' is stored in clear; store its hash instead: "
        "echo TOKEN | smc-dashboard --hash-token {}",
        path, name, name);
  }
  return auth;
}

Auth::Digest Auth::digest(std::string_view token) {
  Digest d{};
  unsigned int n = 0;
  if (EVP_Digest(token.data(), token.size(), d.data(), &n, EVP_sha256(), nullptr) != 1 ||
      n != d.size()) {
    throw std::runtime_error("SHA-256 (OpenSSL EVP_Digest) failed");
  }
  return d;
}

std::string Auth::hash_line(std::string_view name, std::string_view token) {
  token = trim(token);
  if (!valid_name(name)) {
    throw std::invalid_argument("operator name '" + std::string(name) +
                                "' must be 1-31 characters of A-Z a-z 0-9 . _ - @");
  }
  if (!valid_token(token)) {
    throw std::invalid_argument("the token must be at least " + std::to_string(kMinTokenLength) +
                                " printable characters without spaces");
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string line = std::string(name) + " " + std::string(kSha256Prefix);
  for (const unsigned char b : digest(token)) {
    line += kHex[b >> 4];
    line += kHex[b & 15];
  }
  return line;
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
  if (token.size() > 4096) return std::nullopt;
  const Digest d = digest(token);
  const Operator* found = nullptr;
  for (const auto& op : operators_) {  // no early exit: same time for every token
    if (same(d, op.token_sha256) && found == nullptr) found = &op;
  }
  if (found == nullptr) return std::nullopt;
  return found->name;
}

}  // namespace smc::dashboard
