#pragma once
// Move-only owner of one DDS entity handle. Deleting never throws.

#include <cstdint>
#include <utility>

namespace smc::transport {

using EntityHandle = int32_t;  // dds_entity_t

class Entity {
 public:
  Entity() = default;
  explicit Entity(EntityHandle h) noexcept : handle_(h) {}
  Entity(Entity&& o) noexcept : handle_(std::exchange(o.handle_, 0)) {}
  Entity& operator=(Entity&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, 0);
    }
    return *this;
  }
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  ~Entity() { reset(); }

  EntityHandle handle() const noexcept { return handle_; }
  explicit operator bool() const noexcept { return handle_ > 0; }
  void reset() noexcept;

 private:
  EntityHandle handle_ = 0;
};

}  // namespace smc::transport
