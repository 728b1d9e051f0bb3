#pragma once
// The embedded web files, generated at build time (cmake/embed_assets.cmake)
// from dashboard/web/src and the npm packages installed by `npm ci`.

#include <cstddef>
#include <span>
#include <string_view>

namespace smc::dashboard {

struct EmbeddedFile {
  std::string_view path;  // URL path, e.g. "/vendor/uPlot.iife.min.js"
  const unsigned char* data;
  std::size_t size;
};

std::span<const EmbeddedFile> web_assets() noexcept;

}  // namespace smc::dashboard
