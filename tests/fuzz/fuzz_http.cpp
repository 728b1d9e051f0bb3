// The dashboard's HTTP decoders: the request target (path segments and
// query, percent-decoded), the operator token file and Authorization
// header, and a whole request as the server reads it (Boost.Beast's parser
// with the server's limits, then the target and the Authorization header).
// The first byte picks which; the rest is the input.
#include <boost/asio/buffer.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/string_body.hpp>
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
  switch (data[0] % 3) {
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
    case 2: {
      // As HttpServer reads a request: the same body and header limits.
      namespace http = boost::beast::http;
      http::request_parser<http::string_body> parser;
      parser.body_limit(4096);
      parser.header_limit(8192);
      parser.eager(true);
      boost::beast::error_code ec;
      std::size_t used = 0;
      while (!ec && used < in.size() && !parser.is_done()) {
        const std::size_t n =
            parser.put(boost::asio::buffer(in.data() + used, in.size() - used), ec);
        if (n == 0 && !ec) break;  // needs more than there is
        used += n;
      }
      if (ec || !parser.is_header_done()) return 0;
      const auto& req = parser.get();
      const auto target = req.target();
      (void)smc::dashboard::parse_target(std::string_view(target.data(), target.size()));
      const auto auth = req[http::field::authorization];
      static const auto kOperators = smc::dashboard::Auth::parse(
          "alice sha256:b19dd0d3436da6a4171b05d7ad2f0c8a52e88e21834b66c2ce9ad3df58c46eea\n",
          "fuzz");
      (void)kOperators.authenticate(std::string_view(auth.data(), auth.size()));
      break;
    }
  }
  return 0;
}
