// The dashboard's HTTP decoders: the request target (path segments and
// query, percent-decoded) and the operator token file and Authorization
// header. The first byte picks which; the rest is the input.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "auth.hpp"
#include "http_target.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view in(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 2) {
    case 0: {
      const auto t = smc::dashboard::parse_target(in);
      if (!t) return 0;
      // A parsed target starts at the root; segments are never empty and
      // nothing decodes to NUL.
      check(!t->path.empty() && t->path.front() == '/');
      for (const auto& s : t->segments) check(!s.empty() && s.find('\0') == std::string::npos);
      for (const auto& [k, v] : t->query) {
        check(k.find('\0') == std::string::npos && v.find('\0') == std::string::npos);
      }
      break;
    }
    case 1: {
      // A token file, then its last line's token tried as a header.
      try {
        const auto auth = smc::dashboard::Auth::parse(in, "fuzz");
        const std::size_t nl = in.rfind('\n');
        const std::string_view last = nl == std::string_view::npos ? in : in.substr(nl + 1);
        (void)auth.authenticate(last);
        (void)auth.authenticate(std::string("Bearer ") + std::string(last));
      } catch (const std::runtime_error&) {
        // a bad line, reported: fine
      }
      break;
    }
  }
  return 0;
}
