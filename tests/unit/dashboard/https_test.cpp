// HTTPS: with a certificate from the project's web CA (deploy/security/pki.sh
// https), the dashboard serves its API, its stream and operator commands over
// TLS to a client that trusts that CA and checks the host name; a client
// that trusts another CA does not get through; plain HTTP on the port is
// told to use HTTPS; a certificate or key it cannot use stops it at start,
// naming the file.

#include <gtest/gtest.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "dashboard_fixture.hpp"

using namespace smc::test;
using namespace std::chrono_literals;

namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace bhttp = beast::http;
namespace ssl = asio::ssl;

// A web CA and the dashboard's certificate for 127.0.0.1 and localhost,
// made by the project's script, in a folder of their own.
struct WebPki {
  explicit WebPki(const std::string& name) {
    dir = (std::filesystem::temp_directory_path() /
           ("smc-https-" + name + "-" + std::to_string(::getpid())))
              .string();
    std::filesystem::remove_all(dir);
    const std::string cmd = std::string(SMC_SOURCE_DIR) + "/deploy/security/pki.sh https '" + dir +
                            "' dashboard 127.0.0.1 localhost >/dev/null";
    ok = std::system(cmd.c_str()) == 0;
  }
  ~WebPki() { std::filesystem::remove_all(dir); }
  std::string ca() const { return dir + "/ca/web_ca.pem"; }
  std::string cert() const { return dir + "/dashboard/https.pem"; }
  std::string key() const { return dir + "/dashboard/https.key"; }
  std::string dir;
  bool ok = false;
};

struct TlsReply {
  std::string error;  // empty: the request went through
  int status = 0;
  std::string body;
};

// One request over TLS, trusting `ca_file` only and checking that the
// certificate names `host`.
TlsReply https(uint16_t port, const std::string& ca_file, const std::string& method,
               const std::string& target, const std::string& body = {},
               const std::string& token = {}, const std::string& host = "127.0.0.1") {
  TlsReply out;
  asio::io_context ioc;
  ssl::context ctx(ssl::context::tls_client);
  ctx.load_verify_file(ca_file);
  ctx.set_verify_mode(ssl::verify_peer);
  beast::ssl_stream<beast::tcp_stream> stream(ioc, ctx);
  stream.set_verify_callback(ssl::host_name_verification(host));
  beast::get_lowest_layer(stream).expires_after(10s);
  beast::error_code ec;
  beast::get_lowest_layer(stream).socket().connect(
      asio::ip::tcp::endpoint(asio::ip::address_v4::loopback(), port), ec);
  if (!ec) stream.handshake(ssl::stream_base::client, ec);
  if (ec) {
    out.error = ec.message();
    return out;
  }
  bhttp::request<bhttp::string_body> req{method == "POST" ? bhttp::verb::post : bhttp::verb::get,
                                         target, 11};
  req.set(bhttp::field::host, host);
  if (!token.empty()) req.set(bhttp::field::authorization, "Bearer " + token);
  if (!body.empty()) req.set(bhttp::field::content_type, "application/json");
  req.body() = body;
  req.prepare_payload();
  bhttp::write(stream, req, ec);
  beast::flat_buffer buffer;
  bhttp::response<bhttp::string_body> res;
  if (!ec) bhttp::read(stream, buffer, res, ec);
  if (ec) {
    out.error = ec.message();
    return out;
  }
  out.status = static_cast<int>(res.result_int());
  out.body = res.body();
  return out;
}

smc::dashboard::Options tls_options(const WebPki& pki) {
  smc::dashboard::Options o;
  o.tls_cert = pki.cert();
  o.tls_key = pki.key();
  return o;
}

}  // namespace

TEST(DashboardHttps, ServesTheApiAndCommandsToAClientThatTrustsTheProjectsWebCa) {
  WebPki pki("api");
  ASSERT_TRUE(pki.ok);
  DashboardFixture f(true, tls_options(pki));
  ASSERT_TRUE(eventually([&] {
    f.cell().status("mill-t");
    return https(f.port(), pki.ca(), "GET", "/api/mills/mill-t").status == 200;
  }));
  const auto by_name = https(f.port(), pki.ca(), "GET", "/api/mills", {}, {}, "localhost");
  EXPECT_EQ(by_name.error, "");
  EXPECT_EQ(by_name.status, 200);
  EXPECT_NE(by_name.body.find("mill-t"), std::string::npos) << by_name.body;

  ASSERT_TRUE(f.cell().commands.wait_for_writers(1, 5s));
  const auto cmd = https(f.port(), pki.ca(), "POST", "/api/mills/mill-t/commands",
                         R"({"action":"feed_hold_on"})", kAliceToken);
  EXPECT_EQ(cmd.error, "");
  EXPECT_EQ(cmd.status, 202) << cmd.body;
  EXPECT_NE(cmd.body.find("\"operator\":\"alice\""), std::string::npos) << cmd.body;
  const auto refused = https(f.port(), pki.ca(), "POST", "/api/mills/mill-t/commands",
                             R"({"action":"feed_hold_on"})", "not-a-token-0123456789");
  EXPECT_EQ(refused.status, 401) << refused.body;
}

TEST(DashboardHttps, TheStreamRunsOverTls) {
  WebPki pki("stream");
  ASSERT_TRUE(pki.ok);
  DashboardFixture f(false, tls_options(pki));
  asio::io_context ioc;
  ssl::context ctx(ssl::context::tls_client);
  ctx.load_verify_file(pki.ca());
  ctx.set_verify_mode(ssl::verify_peer);
  beast::ssl_stream<beast::tcp_stream> stream(ioc, ctx);
  stream.set_verify_callback(ssl::host_name_verification("127.0.0.1"));
  beast::get_lowest_layer(stream).expires_after(10s);
  beast::get_lowest_layer(stream).socket().connect(
      asio::ip::tcp::endpoint(asio::ip::address_v4::loopback(), f.port()));
  stream.handshake(ssl::stream_base::client);
  bhttp::request<bhttp::empty_body> req{bhttp::verb::get, "/api/stream", 11};
  req.set(bhttp::field::host, "127.0.0.1");
  bhttp::write(stream, req);
  // The header, then the hello event; then a summary of a mill as an event.
  std::string got;
  char buf[4096];
  beast::error_code ec;
  while (got.find("event: hello") == std::string::npos && !ec) {
    got.append(buf, stream.read_some(asio::buffer(buf), ec));
  }
  ASSERT_FALSE(ec) << ec.message() << "; got: " << got;
  EXPECT_NE(got.find("text/event-stream"), std::string::npos) << got;
  f.cell().status("mill-s");
  while (got.find("mill-s") == std::string::npos && !ec) {
    got.append(buf, stream.read_some(asio::buffer(buf), ec));
  }
  EXPECT_FALSE(ec) << ec.message();
  EXPECT_NE(got.find("mill-s"), std::string::npos);
}

TEST(DashboardHttps, AClientTrustingAnotherCaAndPlainHttpDoNotGetThrough) {
  WebPki pki("refuse");
  WebPki other("other");
  ASSERT_TRUE(pki.ok && other.ok);
  DashboardFixture f(true, tls_options(pki));
  const auto foreign = https(f.port(), other.ca(), "GET", "/api/mills");
  EXPECT_NE(foreign.error.find("certificate verify failed"), std::string::npos) << foreign.error;
  EXPECT_EQ(foreign.status, 0);
  // The certificate names 127.0.0.1 and localhost, not this name.
  const auto wrong_name = https(f.port(), pki.ca(), "GET", "/api/mills", {}, {}, "mill-host");
  EXPECT_NE(wrong_name.error, "");
  EXPECT_EQ(wrong_name.status, 0);

  const auto plain = http(f.port(), "GET", "/api/mills");
  EXPECT_EQ(plain.status, 400);
  EXPECT_NE(plain.body.find("HTTPS only"), std::string::npos) << plain.body;
  // And the server goes on serving HTTPS.
  EXPECT_EQ(https(f.port(), pki.ca(), "GET", "/api/mills").status, 200);
}

TEST(DashboardHttps, ACertificateOrKeyItCannotUseStopsItAtStartNamingTheFile) {
  WebPki pki("bad");
  ASSERT_TRUE(pki.ok);
  smc::dashboard::Options o;
  o.http = "127.0.0.1:0";
  o.partition = unique_partition("https-bad");
  o.tls_cert = pki.key();  // a key where the certificate goes
  o.tls_key = pki.key();
  try {
    smc::dashboard::Dashboard d(o);
    FAIL() << "a key used as the certificate was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(pki.key() + ": cannot use it as the HTTPS certificate"),
              std::string::npos)
        << e.what();
  }
  o.tls_cert = pki.cert();
  o.tls_key.clear();
  EXPECT_THROW(smc::dashboard::Dashboard{o}, std::invalid_argument);
}
