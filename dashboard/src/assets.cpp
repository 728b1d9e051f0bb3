#include "assets.hpp"

#include <fstream>
#include <sstream>

#include "web_assets.hpp"

namespace smc::dashboard {

std::string content_type_for(std::string_view path) {
  auto ends = [&](std::string_view ext) {
    return path.size() >= ext.size() && path.substr(path.size() - ext.size()) == ext;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js") || ends(".mjs")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".svg")) return "image/svg+xml";
  if (ends(".png")) return "image/png";
  if (ends(".json")) return "application/json";
  if (ends(".txt")) return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

Assets::Assets(std::string web_root) : root_(std::move(web_root)) {}

std::optional<Asset> Assets::find(std::string_view path) const {
  if (path == "/") path = "/index.html";
  if (path.empty() || path.front() != '/' || path.find("..") != std::string_view::npos ||
      path.find('\\') != std::string_view::npos || path.find('\0') != std::string_view::npos) {
    return std::nullopt;
  }
  if (root_.empty()) {
    for (const auto& a : web_assets()) {
      if (a.path == path) {
        return Asset{content_type_for(path),
                     std::string(reinterpret_cast<const char*>(a.data), a.size)};
      }
    }
    return std::nullopt;
  }
  std::ifstream in(root_ + std::string(path), std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  return Asset{content_type_for(path), ss.str()};
}

}  // namespace smc::dashboard
