#pragma once
// One error type for every failing Cyclone DDS call.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace smc::transport {

// Thrown when a DDS call returns a negative dds_return_t. what() reads
// "dds_create_topic(smc_force_summary): Bad parameter (-3)".
class DdsError : public std::runtime_error {
 public:
  DdsError(std::string call, int32_t code, const std::string& message);
  const std::string& call() const noexcept { return call_; }
  int32_t code() const noexcept { return code_; }

 private:
  std::string call_;
  int32_t code_;
};

}  // namespace smc::transport
