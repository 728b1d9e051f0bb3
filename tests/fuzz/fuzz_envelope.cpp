// libFuzzer target: the envelope checker (services/transport document.hpp),
// the first code that touches a configuration-plane document arriving over
// DDS from anyone on the network: schema, version, size and CRC-32, then
// the Protobuf parse. The input fills the envelope's fields, then the payload.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "smc/transport/document.hpp"
#include "smc_config.pb.h"
#include "smc_data.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  smc_data_Envelope env{};
  constexpr std::size_t kHeader = 64 + 64 + 4 + 4 + 4;
  if (size < kHeader) return 0;
  std::memcpy(env.key, data, 64);
  std::memcpy(env.schema, data + 64, 64);
  env.key[63] = env.schema[63] = '\0';  // DDS bounded strings are terminated
  std::memcpy(&env.version, data + 128, 4);
  std::memcpy(&env.payload_size, data + 132, 4);
  std::memcpy(&env.crc32, data + 136, 4);
  // A payload the size the sender claims is not what is sent: keep both.
  env.payload._buffer = const_cast<std::uint8_t*>(data + kHeader);
  env.payload._length = static_cast<std::uint32_t>(size - kHeader);
  env.payload._maximum = env.payload._length;
  smc::config::SupervisorConfig out;
  const smc::transport::Schema expected{"smc.config.SupervisorConfig", 1};
  (void)smc::transport::decode_envelope(env, expected, out);
  return 0;
}
