#pragma once
// Operator tokens. The dashboard is read-only for everyone; a request that
// carries "Authorization: Bearer TOKEN" with a configured token may also send
// operator commands, which are logged and put on DDS under that operator's
// name. Tokens are read once at start from a file of "NAME sha256:HEX" lines
// (the SHA-256 of the token: the file does not hold the tokens themselves;
// hash_line() writes one); a "NAME TOKEN" line in clear is still accepted,
// with a warning.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace smc::dashboard {

class Auth {
 public:
  static constexpr std::size_t kMinTokenLength = 16;
  static constexpr std::size_t kMaxNameLength = 31;  // OperatorCommand.operator_name

  Auth() = default;
  // One "NAME TOKEN" per line; blank lines and lines starting with '#' are
  // skipped. Throws std::runtime_error listing every bad line as
  // "source:line: what is wrong"; no half-read token set is ever used.
  static Auth parse(std::string_view text, std::string_view source);
  static Auth from_file(const std::string& path);
  // The token file's line for this operator: "NAME sha256:HEX". Throws
  // std::invalid_argument naming what is wrong with the name or token.
  static std::string hash_line(std::string_view name, std::string_view token);

  bool enabled() const noexcept { return !operators_.empty(); }
  std::size_t size() const noexcept { return operators_.size(); }
  // Operators whose token the file holds in clear ("NAME TOKEN").
  const std::vector<std::string>& in_clear() const noexcept { return in_clear_; }

  // The operator whose token the Authorization header value carries
  // ("Bearer TOKEN"); nullopt for a missing, malformed or unknown token.
  // The comparison takes the same time whichever token is near.
  std::optional<std::string> authenticate(std::string_view authorization) const;

 private:
  using Digest = std::array<unsigned char, 32>;  // SHA-256
  static Digest digest(std::string_view token);
  struct Operator {
    std::string name;
    Digest token_sha256;
  };
  std::vector<Operator> operators_;
  std::vector<std::string> in_clear_;
};

}  // namespace smc::dashboard
