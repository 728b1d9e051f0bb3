#pragma once
// The REST API and the page's files, as plain request -> response functions
// (no sockets here: http_server.cpp does the I/O). Routes, the stream's
// query and the security model are described in dashboard/README.md.

#include <functional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace smc::dashboard {

class JobHistory;

class Assets;
class Auth;
class CellState;
class CommandSink;

struct HttpRequest {
  std::string method;  // "GET", "POST", ...
  std::string target;  // path and query, as sent
  std::string authorization;
  std::string content_type;
  std::string body;
  std::string remote;  // "address:port", for logs
};

struct HttpResponse {
  unsigned status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
};

// An error answer: {"error": message, "status": status}.
HttpResponse error_response(unsigned status, const std::string& message);

// What a client of GET /api/stream asked for.
struct StreamRequest {
  std::vector<std::string> mills;  // empty: every mill
  bool raw = false;                // include ForceBatch events
};

class Api {
 public:
  struct Deps {
    CellState& state;
    const Auth& auth;
    CommandSink& commands;
    const Assets& assets;
    std::function<std::string()> stats;  // the server's /api/stats body
    JobHistory* history = nullptr;       // the cell's database (--cell-db), or none
  };
  explicit Api(Deps deps) : deps_(std::move(deps)) {}

  // True for GET /api/stream (the server turns the connection into a stream).
  static bool is_stream(const HttpRequest& req);
  // The stream's parameters, or the error to answer with.
  std::variant<StreamRequest, HttpResponse> stream_request(const HttpRequest& req) const;

  // Answers `req` through `reply`, at once or later from another thread
  // (operator commands complete on the DDS thread).
  void handle(const HttpRequest& req, std::function<void(HttpResponse)> reply);

 private:
  HttpResponse command(const HttpRequest& req, const std::string& mill,
                       std::function<void(HttpResponse)>& reply, bool& pending);
  Deps deps_;
};

}  // namespace smc::dashboard
