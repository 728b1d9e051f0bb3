#pragma once
// Operator tokens. The dashboard is read-only for everyone; a request that
// carries "Authorization: Bearer TOKEN" with a configured token may also send
// operator commands, which are logged and put on DDS under that operator's
// name. Tokens are read once at start from a file of "NAME TOKEN" lines.

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

  bool enabled() const noexcept { return !operators_.empty(); }
  std::size_t size() const noexcept { return operators_.size(); }

  // The operator whose token the Authorization header value carries
  // ("Bearer TOKEN"); nullopt for a missing, malformed or unknown token.
  // The comparison takes the same time whichever token is near.
  std::optional<std::string> authenticate(std::string_view authorization) const;

 private:
  struct Operator {
    std::string name;
    std::string token;
  };
  std::vector<Operator> operators_;
};

}  // namespace smc::dashboard
