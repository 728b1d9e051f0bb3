#pragma once
// The configuration plane's topics, typed: each Protobuf document type knows
// its topic, and its schema (name and version) comes from the Protobuf
// descriptor, so no process spells "smc.config.SupervisorConfig" by hand.
//
//   wire::DocumentPublisher<config::SupervisorConfig> configs(participant);
//   configs.publish(machine_id, config_id, cfg);
//   wire::DocumentSubscriber<config::JobAssignment> jobs(participant);
//   jobs.take(on_accept, on_reject);   // transport::DocumentReader's API
//
// Includes smc_config.pb.h: only for processes that handle documents.

#include <string>
#include <string_view>

#include "smc/transport/document.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

namespace smc::wire {

// The topic each document type travels on (idl/README.md lists keys and QoS).
template <class M>
struct DocumentTopic;
template <>
struct DocumentTopic<smc::config::SupervisorConfig> {
  static constexpr const char* kName = kConfigTopic;  // key: machine id
  static constexpr bool kPerMachine = true;
};
template <>
struct DocumentTopic<smc::config::JobAssignment> {
  static constexpr const char* kName = kJobTopic;  // key: machine id
  static constexpr bool kPerMachine = true;
};
template <>
struct DocumentTopic<smc::config::JobStatus> {
  static constexpr const char* kName = kJobStatusTopic;  // key: job id
  static constexpr bool kPerMachine = false;
};
template <>
struct DocumentTopic<smc::config::PartProgram> {
  static constexpr const char* kName = kProgramTopic;  // key: machine id
  static constexpr bool kPerMachine = true;
};
template <>
struct DocumentTopic<smc::config::CatalogView> {
  static constexpr const char* kName = kCatalogTopic;  // key: "cell"
  static constexpr bool kPerMachine = false;
};

// The schema a document of type M is sent and checked with.
template <class M>
transport::Schema schema() {
  return transport::Schema{std::string(M::descriptor()->full_name()),
                           static_cast<uint32_t>(smc::config::SCHEMA_VERSION_CURRENT)};
}

namespace detail {
struct EnvelopeTopic {
  EnvelopeTopic(transport::Participant& p, const char* name) : topic(p, name) {}
  transport::Topic<smc_data_Envelope> topic;
};
}  // namespace detail

template <class M>
class DocumentPublisher : private detail::EnvelopeTopic {
 public:
  explicit DocumentPublisher(transport::Participant& p)
      : detail::EnvelopeTopic(p, DocumentTopic<M>::kName),
        writer_(topic, schema<M>(), DocumentTopic<M>::kPerMachine) {}
  void publish(std::string_view key, std::string_view document_id, const M& doc) {
    writer_.publish(key, document_id, doc);
  }
  transport::WriterBase& writer() noexcept { return writer_.writer(); }
  // The writer of the documents with this key (its machine's, for documents
  // keyed by machine).
  transport::WriterBase& writer_for(const std::string& key) { return writer_.writer_for(key); }

 private:
  transport::DocumentWriter writer_;
};

template <class M>
class DocumentSubscriber : private detail::EnvelopeTopic, public transport::DocumentReader<M> {
 public:
  explicit DocumentSubscriber(transport::Participant& p)
      : detail::EnvelopeTopic(p, DocumentTopic<M>::kName),
        transport::DocumentReader<M>(topic, schema<M>()) {}
};

}  // namespace smc::wire
