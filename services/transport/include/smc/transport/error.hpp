#pragma once
// One error type for every failing Cyclone DDS call (services/transport/src/
// check.hpp is the one path every dds_return_t goes through).

#include <cstdint>
#include <stdexcept>
#include <string>

namespace smc::transport {

// What kind of failure, from the DDS return code, so a caller can decide
// without parsing text: a bad argument or precondition is the caller's
// mistake (fix the code or the input); out of resources and timeouts may
// pass; the rest is the middleware's.
enum class ErrorKind : uint8_t {
  kBadParameter,        // DDS_RETCODE_BAD_PARAMETER, _ILLEGAL_OPERATION, _INCONSISTENT_POLICY
  kPreconditionNotMet,  // DDS_RETCODE_PRECONDITION_NOT_MET, _NOT_ENABLED, _IMMUTABLE_POLICY
  kAlreadyDeleted,      // DDS_RETCODE_ALREADY_DELETED: the entity is gone
  kOutOfResources,      // DDS_RETCODE_OUT_OF_RESOURCES
  kTimeout,             // DDS_RETCODE_TIMEOUT
  kUnsupported,         // DDS_RETCODE_UNSUPPORTED
  kOther,               // DDS_RETCODE_ERROR and anything else
};
const char* to_string(ErrorKind kind) noexcept;
ErrorKind error_kind(int32_t dds_return_code) noexcept;

// Thrown when a DDS call returns a negative dds_return_t. what() reads
// "dds_create_topic(smc_force_summary): Bad parameter (-3)".
class DdsError : public std::runtime_error {
 public:
  DdsError(std::string call, int32_t code, const std::string& message);
  const std::string& call() const noexcept { return call_; }
  int32_t code() const noexcept { return code_; }
  ErrorKind kind() const noexcept { return error_kind(code_); }

 private:
  std::string call_;
  int32_t code_;
};

}  // namespace smc::transport
