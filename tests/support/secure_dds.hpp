#pragma once
// Benchmark helper: the same measurement over plain DDS and under DDS
// Security, in one run. The secure mode makes a PKI of its own with
// deploy/security/pki.sh (the cell, one edge per machine, the dashboard) and
// runs on a DDS domain of its own, so that the plain and the secure
// participants of one process never meet. Every profile is the loopback one.

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "smc/transport/participant.hpp"

namespace smc::test {

class SecureDds {
 public:
  // Plain DDS on domain 0.
  SecureDds() = default;
  // DDS Security on `domain`, with identities for the cell, the dashboard
  // and the edges of `machines`.
  SecureDds(std::uint32_t domain, const std::vector<std::string>& machines) : domain_(domain) {
    pki_ = (std::filesystem::temp_directory_path() /
            ("smc-bench-pki-" + std::to_string(::getpid()) + "-" + std::to_string(domain)))
               .string();
    std::filesystem::remove_all(pki_);
    std::string list;
    for (const auto& m : machines) list += (list.empty() ? "" : ",") + m;
    const std::string cmd = std::string(SMC_SOURCE_DIR) + "/deploy/security/pki.sh init '" + pki_ +
                            "'" + (list.empty() ? "" : " --machines " + list) + " >/dev/null";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("pki.sh init failed: " + cmd);
  }
  ~SecureDds() {
    if (!pki_.empty()) std::filesystem::remove_all(pki_);
  }
  SecureDds(const SecureDds&) = delete;
  SecureDds& operator=(const SecureDds&) = delete;

  bool secure() const { return !pki_.empty(); }
  const char* name() const { return secure() ? "DDS Security" : "plain DDS"; }
  std::uint32_t domain() const { return domain_; }

  // A participant of this process with `identity` ("cell", "dashboard").
  transport::ParticipantOptions participant(const std::string& partition,
                                            const std::string& identity = "cell") const {
    transport::ParticipantOptions o;
    o.domain_id = domain_;
    o.partition = partition;
    if (secure()) o.config = "file://" + pki_ + "/" + identity + "/cyclonedds.xml";
    return o;
  }

  // A child's argv with `identity`'s profile ("cell", "edge-mill-1"); the
  // program's own --domain flag is the caller's (domain()).
  std::vector<std::string> child(std::vector<std::string> argv, const std::string& identity) const {
    if (!secure()) return argv;
    argv.insert(argv.begin(), {"/usr/bin/env", "CYCLONEDDS_URI=file://" + pki_ + "/" + identity +
                                                   "/cyclonedds.xml"});
    return argv;
  }

 private:
  std::uint32_t domain_ = 0;
  std::string pki_;
};

}  // namespace smc::test
