// libFuzzer target: the Protobuf document loaders (services/documents) and
// the shared configuration check (services/supervision validate), the path
// every supervisor configuration, job, catalog and model file takes into the
// cell and the edge. The first byte picks the document kind and the format
// (text or JSON); the rest is the document.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "smc/documents/load.hpp"
#include "smc/supervision/config.hpp"
#include "smc_config.pb.h"

namespace {

template <class Message>
bool parse(const std::string& text, bool json, Message& m) {
  try {
    smc::documents::parse(text, json, "fuzz", m);
    return true;
  } catch (const smc::documents::DocumentError&) {
    return false;  // the expected refusal, with a message
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool json = (data[0] & 1) != 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  switch ((data[0] >> 1) % 5) {
    case 0: {
      smc::config::SupervisorConfig c;
      if (parse(text, json, c)) {
        try {
          (void)smc::supervision::validate(c);
        } catch (const std::exception&) {
          // ConfigError: refused with its field paths
        }
      }
      break;
    }
    case 1: {
      smc::config::Job j;
      (void)parse(text, json, j);
      break;
    }
    case 2: {
      smc::config::Catalog c;
      (void)parse(text, json, c);
      break;
    }
    case 3: {
      smc::config::MillingModel m;
      (void)parse(text, json, m);
      break;
    }
    default: {
      smc::config::ForceProcessModel m;
      (void)parse(text, json, m);
      break;
    }
  }
  return 0;
}
