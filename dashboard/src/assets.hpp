#pragma once
// The web page's files: embedded into the binary at build time (the default;
// nothing is fetched from anywhere at run time), or read from a folder for
// front-end work (--web-root).

#include <optional>
#include <string>
#include <string_view>

namespace smc::dashboard {

struct Asset {
  std::string content_type;
  std::string body;
};

class Assets {
 public:
  // Empty `web_root`: the embedded files.
  explicit Assets(std::string web_root = {});
  // `path` is the URL path ("/" is "/index.html"); nullopt when absent or
  // when the path tries to leave the root.
  std::optional<Asset> find(std::string_view path) const;

 private:
  std::string root_;
};

// Content type by file extension.
std::string content_type_for(std::string_view path);

}  // namespace smc::dashboard
