#pragma once
// A minimal HTTP/1.1 and Server-Sent Events client over POSIX sockets, for
// the dashboard tests: it sends exactly the bytes a test asks for (so bad
// requests can be bad) and reads with deadlines, never blocking forever.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace smc::test {

using namespace std::chrono_literals;

class Socket {
 public:
  // Connects to 127.0.0.1:port; `rcvbuf` > 0 shrinks the receive buffer
  // first (a client that reads slowly fills it quickly).
  explicit Socket(uint16_t port, int rcvbuf = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd_ < 0) throw std::runtime_error("socket failed");
    if (rcvbuf > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd_);
      throw std::runtime_error("connect to port " + std::to_string(port) + " failed");
    }
  }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  ~Socket() { close(); }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  void send_all(const std::string& data) {
    size_t off = 0;
    while (off < data.size()) {
      const ssize_t n = ::send(fd_, data.data() + off, data.size() - off, MSG_NOSIGNAL);
      if (n <= 0) throw std::runtime_error("send failed");
      off += static_cast<size_t>(n);
    }
  }

  // Appends what arrives before the deadline; false on timeout, EOF or error
  // (eof() tells which).
  bool read_some(std::string& out, std::chrono::steady_clock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return false;
    char buf[16384];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) {
      eof_ = true;
      return false;
    }
    out.append(buf, static_cast<size_t>(n));
    return true;
  }
  bool eof() const { return eof_; }

 private:
  int fd_ = -1;
  bool eof_ = false;
};

struct HttpResponse {
  int status = 0;
  std::map<std::string, std::string> headers;  // names lower-cased
  std::string body;
  std::string header(const std::string& name) const {
    auto it = headers.find(name);
    return it == headers.end() ? std::string() : it->second;
  }
};

inline std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Parses "HTTP/1.1 200 OK\r\nName: value\r\n...\r\n\r\n"; returns the size
// of the head, or 0 when it is not complete yet.
inline size_t parse_head(const std::string& raw, HttpResponse& r) {
  const size_t end = raw.find("\r\n\r\n");
  if (end == std::string::npos) return 0;
  r.status = std::stoi(raw.substr(9, 3));
  size_t pos = raw.find("\r\n") + 2;
  while (pos < end) {
    const size_t eol = raw.find("\r\n", pos);
    const std::string line = raw.substr(pos, eol - pos);
    const size_t colon = line.find(':');
    std::string value = line.substr(colon + 1);
    while (!value.empty() && value.front() == ' ') value.erase(0, 1);
    r.headers[lower(line.substr(0, colon))] = value;
    pos = eol + 2;
  }
  return end + 4;
}

// Sends `raw` and reads one response (by Content-Length, else to EOF).
inline HttpResponse raw_request(uint16_t port, const std::string& raw,
                                std::chrono::milliseconds timeout = 5000ms) {
  Socket s(port);
  s.send_all(raw);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::string in;
  HttpResponse r;
  size_t head = 0;
  while (true) {
    if (head == 0) head = parse_head(in, r);
    if (head != 0) {
      const std::string cl = r.header("content-length");
      if (!cl.empty() && in.size() >= head + std::stoul(cl)) break;
    }
    if (!s.read_some(in, deadline)) {
      if (s.eof()) break;
      throw std::runtime_error("no complete response within the deadline; got: " + in);
    }
  }
  if (head == 0) throw std::runtime_error("no response head; got: " + in);
  r.body = in.substr(head);
  return r;
}

inline HttpResponse http(uint16_t port, const std::string& method, const std::string& target,
                         const std::string& body = {}, const std::string& extra_headers = {}) {
  std::string req = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n";
  req += extra_headers;
  if (!body.empty() || method == "POST")
    req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  req += "\r\n" + body;
  return raw_request(port, req);
}

struct SseEvent {
  std::string event;
  std::string data;
};

// One Server-Sent Events stream.
class SseClient {
 public:
  SseClient(uint16_t port, const std::string& target, int rcvbuf = 0) : socket_(port, rcvbuf) {
    socket_.send_all("GET " + target +
                     " HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: text/event-stream\r\n\r\n");
  }

  // The response head (status 200 for a stream); throws past the deadline.
  const HttpResponse& head(std::chrono::milliseconds timeout = 5000ms) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (head_size_ == 0) {
      head_size_ = parse_head(buf_, head_);
      if (head_size_ != 0) {
        buf_.erase(0, head_size_);
        break;
      }
      if (!socket_.read_some(buf_, deadline)) throw std::runtime_error("no stream head: " + buf_);
    }
    return head_;
  }

  // The next event (comments and retry lines skipped), or nullopt when the
  // deadline passes or the stream ends.
  std::optional<SseEvent> next(std::chrono::steady_clock::time_point deadline) {
    head();
    while (true) {
      const size_t end = buf_.find("\n\n");
      if (end != std::string::npos) {
        const std::string frame = buf_.substr(0, end);
        buf_.erase(0, end + 2);
        SseEvent e;
        size_t pos = 0;
        while (pos <= frame.size()) {
          size_t eol = frame.find('\n', pos);
          if (eol == std::string::npos) eol = frame.size();
          const std::string line = frame.substr(pos, eol - pos);
          if (line.rfind("event: ", 0) == 0) e.event = line.substr(7);
          if (line.rfind("data: ", 0) == 0) e.data += line.substr(6);
          pos = eol + 1;
        }
        if (!e.event.empty() || !e.data.empty()) return e;
        continue;
      }
      if (!socket_.read_some(buf_, deadline)) return std::nullopt;
    }
  }

  // The next event named `name`, skipping others.
  std::optional<SseEvent> next_named(const std::string& name,
                                     std::chrono::steady_clock::time_point deadline) {
    while (auto e = next(deadline)) {
      if (e->event == name) return e;
    }
    return std::nullopt;
  }

  bool ended() const { return socket_.eof(); }
  void close() { socket_.close(); }

 private:
  Socket socket_;
  std::string buf_;
  HttpResponse head_;
  size_t head_size_ = 0;
};

}  // namespace smc::test
