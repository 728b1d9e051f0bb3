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

DdsError::DdsError(std::string call, int32_t code, const std::string& message)
    : std::runtime_error(call + ": " + message + " (" + std::to_string(code) + ")"),
      call_(std::move(call)),
      code_(code) {}

}  // namespace smc::transport
