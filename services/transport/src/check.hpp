#pragma once
// The one error path: every dds_return_t goes through check().

#include <dds/dds.h>

#include <string>

#include "smc/transport/error.hpp"

namespace smc::transport::detail {

// Returns rc when non-negative; throws DdsError naming `call` otherwise.
inline dds_return_t check(dds_return_t rc, const char* call, const std::string& what = {}) {
  if (rc < 0) {
    std::string name = what.empty() ? std::string(call) : std::string(call) + "(" + what + ")";
    throw DdsError(name, rc, dds_strretcode(rc));
  }
  return rc;
}

// RAII for a dds_qos_t built from a profile.
class Qos {
 public:
  Qos() : qos_(dds_create_qos()) {}
  ~Qos() { dds_delete_qos(qos_); }
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  dds_qos_t* get() const noexcept { return qos_; }

 private:
  dds_qos_t* qos_;
};

}  // namespace smc::transport::detail
