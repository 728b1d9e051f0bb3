#pragma once
// Protobuf documents on the DDS Envelope topic: encode with schema name,
// version, size and CRC-32; check all four before a document is accepted.
//
// Protobuf appears here only by forward declaration; callers that use the
// typed helpers include their generated .pb.h themselves.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "smc/transport/endpoint.hpp"

struct smc_data_Envelope;
namespace google::protobuf {
class MessageLite;
}

namespace smc::transport {

enum class DocumentFault : uint8_t {
  kWrongSchema,   // envelope names another message type
  kWrongVersion,  // schema version differs from the reader's
  kTruncated,     // fewer payload bytes than the writer declared
  kBadChecksum,   // CRC-32 of the payload differs
  kUnparsable,    // Protobuf rejected the bytes
  kInvalid,       // parsed, but the application's validation refused it
};

const char* to_string(DocumentFault fault) noexcept;

std::string envelope_key(const smc_data_Envelope& env);
std::string envelope_document_id(const smc_data_Envelope& env);

// Why an envelope was not accepted (a reader's on_reject gets it; not an
// exception: a bad document from the network is expected input).
struct EnvelopeRejection {
  DocumentFault fault;
  std::string key;  // the envelope's key (machine id or job id)
  std::string document_id;
  std::string message;  // names the fault, expected vs found
};

struct Schema {
  std::string name;  // full Protobuf message name
  uint32_t version = 1;
};

// Fills `out` (whose payload buffer the caller must later free with
// free_envelope) from a message. Throws std::length_error past 64 MiB.
void encode_envelope(const google::protobuf::MessageLite& msg, const Schema& schema,
                     std::string_view key, std::string_view document_id, uint64_t sequence_number,
                     smc_data_Envelope& out);
void free_envelope(smc_data_Envelope& env) noexcept;

// Checks schema, version, size and checksum, then parses into `out`.
// Returns the fault, or nullopt when `out` holds the document.
std::optional<EnvelopeRejection> decode_envelope(const smc_data_Envelope& env,
                                                 const Schema& expected,
                                                 google::protobuf::MessageLite& out);

// Publishes documents of one schema on one topic, keyed (machine id or job id).
// `per_machine` (documents keyed by machine, from a participant of the
// cell): each document goes into its machine's partition, through a writer
// made for that machine on first use (see ParticipantOptions::machine).
class DocumentWriter {
 public:
  DocumentWriter(Topic<smc_data_Envelope>& topic, Schema schema, bool per_machine = false);
  void publish(std::string_view key, std::string_view document_id,
               const google::protobuf::MessageLite& msg);
  // The writer a document with this key goes through.
  WriterBase& writer_for(const std::string& key);
  WriterBase& writer() noexcept { return writer_; }

 private:
  Topic<smc_data_Envelope>* topic_;
  Writer<smc_data_Envelope> writer_;
  bool per_machine_;
  std::map<std::string, Writer<smc_data_Envelope>> machines_;
  Schema schema_;
  uint64_t sequence_ = 0;
};

// Receives documents of one schema. A document that fails any check is
// reported and dropped; the last accepted document per key stays in force.
template <class M>
class DocumentReader {
 public:
  DocumentReader(Topic<smc_data_Envelope>& topic, Schema schema)
      : reader_(topic), schema_(std::move(schema)) {}

  // on_accept(const std::string& key, const M& doc) for each good one;
  // on_reject(const EnvelopeRejection&) for each bad one. An optional validator
  // (returns an empty string when fine) turns semantic faults into kInvalid.
  template <class Accept, class Reject>
  size_t take(Accept&& on_accept, Reject&& on_reject) {
    return take_validated(on_accept, on_reject, [](const M&) { return std::string(); });
  }
  template <class Accept, class Reject, class Validate>
  size_t take_validated(Accept&& on_accept, Reject&& on_reject, Validate&& validate) {
    size_t accepted = 0;
    reader_.take([&](const smc_data_Envelope& env, const SampleInfo& info) {
      if (!info.valid_data) return;
      M doc;
      if (auto err = decode_envelope(env, schema_, doc)) {
        on_reject(*err);
        return;
      }
      std::string why = validate(doc);
      std::string key = envelope_key(env);
      if (!why.empty()) {
        on_reject(EnvelopeRejection{DocumentFault::kInvalid, key, envelope_document_id(env), why});
        return;
      }
      ++accepted;
      auto& slot = accepted_[key];
      slot = std::move(doc);
      on_accept(key, slot);
    });
    return accepted;
  }
  // The last accepted document for a key, if any.
  const M* current(const std::string& key) const {
    auto it = accepted_.find(key);
    return it == accepted_.end() ? nullptr : &it->second;
  }
  ReaderBase& reader() noexcept { return reader_; }

 private:
  Reader<smc_data_Envelope> reader_;
  Schema schema_;
  std::map<std::string, M> accepted_;
};

}  // namespace smc::transport
