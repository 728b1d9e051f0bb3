#include "smc/transport/entity.hpp"

#include <dds/dds.h>

#include "smc/transport/error.hpp"

namespace smc::transport {

void Entity::reset() noexcept {
  if (handle_ > 0) {
    // Deleting an entity whose parent is already gone fails harmlessly.
    (void)dds_delete(handle_);
  }
  handle_ = 0;
}

const char* to_string(ErrorKind kind) noexcept {
  switch (kind) {
    case ErrorKind::kBadParameter:
      return "bad parameter";
    case ErrorKind::kPreconditionNotMet:
      return "precondition not met";
    case ErrorKind::kAlreadyDeleted:
      return "already deleted";
    case ErrorKind::kOutOfResources:
      return "out of resources";
    case ErrorKind::kTimeout:
      return "timeout";
    case ErrorKind::kUnsupported:
      return "unsupported";
    case ErrorKind::kOther:
      return "other";
  }
  return "other";
}

ErrorKind error_kind(int32_t rc) noexcept {
  switch (rc) {
    case DDS_RETCODE_BAD_PARAMETER:
    case DDS_RETCODE_ILLEGAL_OPERATION:
    case DDS_RETCODE_INCONSISTENT_POLICY:
      return ErrorKind::kBadParameter;
    case DDS_RETCODE_PRECONDITION_NOT_MET:
    case DDS_RETCODE_NOT_ENABLED:
    case DDS_RETCODE_IMMUTABLE_POLICY:
      return ErrorKind::kPreconditionNotMet;
    case DDS_RETCODE_ALREADY_DELETED:
      return ErrorKind::kAlreadyDeleted;
    case DDS_RETCODE_OUT_OF_RESOURCES:
      return ErrorKind::kOutOfResources;
    case DDS_RETCODE_TIMEOUT:
      return ErrorKind::kTimeout;
    case DDS_RETCODE_UNSUPPORTED:
      return ErrorKind::kUnsupported;
    default:
      return ErrorKind::kOther;
  }
}

DdsError::DdsError(std::string call, int32_t code, const std::string& message)
    : std::runtime_error(call + ": " + message + " (" + std::to_string(code) + ")"),
      call_(std::move(call)),
      code_(code) {}

}  // namespace smc::transport
