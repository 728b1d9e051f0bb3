#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <stdexcept>

#include "bridge.hpp"

namespace smc::edge {

void EdgeService::Impl::load_journal() {
  if (opt.state_file.empty()) return;
  std::FILE* f = std::fopen(opt.state_file.c_str(), "r");
  if (f == nullptr) return;  // first run
  char line[256];
  while (std::fgets(line, sizeof line, f) != nullptr) {
    std::string tag(line);
    while (!tag.empty() && (tag.back() == '\n' || tag.back() == '\r')) tag.pop_back();
    if (tag.empty()) continue;
    started.insert(tag);
    journalled.insert(tag);
  }
  std::fclose(f);
  spdlog::info("{}: journal {}: {} job attempt(s) started by earlier runs", opt.machine_id,
               opt.state_file, journalled.size());
}

void EdgeService::Impl::journal(const std::string& tag) {
  if (opt.state_file.empty()) return;
  std::FILE* f = std::fopen(opt.state_file.c_str(), "a");
  if (f == nullptr) {
    throw std::runtime_error(opt.state_file + ": cannot append to the edge's journal");
  }
  std::fprintf(f, "%s\n", tag.c_str());
  std::fflush(f);
  ::fsync(::fileno(f));
  std::fclose(f);
}

}  // namespace smc::edge
