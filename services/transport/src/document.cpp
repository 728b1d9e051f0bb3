#include "smc/transport/document.hpp"

#include <google/protobuf/message_lite.h>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "check.hpp"
#include "smc/transport/participant.hpp"
#include "smc_data.h"

namespace smc::transport {

namespace {

constexpr size_t kMaxPayload = size_t{64} << 20;

template <size_t N>
void copy_bounded(char (&dst)[N], std::string_view src, const char* field) {
  if (src.size() >= N) {
    throw std::length_error(std::string("envelope field ") + field + " longer than " +
                            std::to_string(N - 1) + " characters: '" + std::string(src) + "'");
  }
  std::memcpy(dst, src.data(), src.size());
  dst[src.size()] = '\0';
}

template <size_t N>
std::string bounded(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

uint32_t crc32_of(const uint8_t* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes uInt lengths; payloads are capped well below 4 GiB.
  crc = crc32(crc, data, static_cast<uInt>(size));
  return static_cast<uint32_t>(crc);
}

}  // namespace

const char* to_string(DocumentFault fault) noexcept {
  switch (fault) {
    case DocumentFault::kWrongSchema:
      return "wrong schema";
    case DocumentFault::kWrongVersion:
      return "wrong version";
    case DocumentFault::kTruncated:
      return "truncated";
    case DocumentFault::kBadChecksum:
      return "bad checksum";
    case DocumentFault::kUnparsable:
      return "unparsable";
    case DocumentFault::kInvalid:
      return "invalid";
  }
  return "unknown";
}

std::string envelope_key(const smc_data_Envelope& env) { return bounded(env.key); }
std::string envelope_document_id(const smc_data_Envelope& env) { return bounded(env.document_id); }

void encode_envelope(const google::protobuf::MessageLite& msg, const Schema& schema,
                     std::string_view key, std::string_view document_id, uint64_t sequence_number,
                     smc_data_Envelope& out) {
  const size_t size = msg.ByteSizeLong();
  if (size > kMaxPayload) {
    throw std::length_error("document " + std::string(document_id) + " is " + std::to_string(size) +
                            " bytes; the envelope limit is " + std::to_string(kMaxPayload));
  }
  out = smc_data_Envelope{};
  copy_bounded(out.key, key, "key");
  copy_bounded(out.schema, schema.name, "schema");
  copy_bounded(out.document_id, document_id, "document_id");
  out.version = schema.version;
  out.sequence_number = sequence_number;
  out.payload_size = static_cast<uint32_t>(size);
  auto* buf = static_cast<uint8_t*>(dds_alloc(size == 0 ? 1 : size));
  if (!msg.SerializeToArray(buf, static_cast<int>(size))) {
    dds_free(buf);
    throw std::runtime_error("cannot serialize document " + std::string(document_id));
  }
  out.payload._buffer = buf;
  out.payload._length = static_cast<uint32_t>(size);
  out.payload._maximum = static_cast<uint32_t>(size);
  out.payload._release = true;
  out.crc32 = crc32_of(buf, size);
}

void free_envelope(smc_data_Envelope& env) noexcept {
  if (env.payload._buffer != nullptr && env.payload._release) dds_free(env.payload._buffer);
  env.payload._buffer = nullptr;
  env.payload._length = env.payload._maximum = 0;
}

std::optional<EnvelopeRejection> decode_envelope(const smc_data_Envelope& env,
                                                 const Schema& expected,
                                                 google::protobuf::MessageLite& out) {
  EnvelopeRejection err{
      DocumentFault::kWrongSchema, bounded(env.key), bounded(env.document_id), {}};
  const std::string where = "document '" + err.document_id + "' for '" + err.key + "': ";
  const std::string schema = bounded(env.schema);
  if (schema != expected.name) {
    err.message = where + "schema is '" + schema + "', expected '" + expected.name + "'";
    return err;
  }
  if (env.version != expected.version) {
    err.fault = DocumentFault::kWrongVersion;
    err.message = where + "schema " + schema + " version " + std::to_string(env.version) +
                  ", this reader understands version " + std::to_string(expected.version);
    return err;
  }
  if (env.payload._length != env.payload_size) {
    err.fault = DocumentFault::kTruncated;
    err.message = where + "payload has " + std::to_string(env.payload._length) +
                  " bytes, the writer declared " + std::to_string(env.payload_size);
    return err;
  }
  const uint32_t crc = crc32_of(env.payload._buffer, env.payload._length);
  if (crc != env.crc32) {
    err.fault = DocumentFault::kBadChecksum;
    char buf[64];
    std::snprintf(buf, sizeof buf, "CRC-32 is %08x, the writer declared %08x", crc, env.crc32);
    err.message = where + buf;
    return err;
  }
  if (!out.ParseFromArray(env.payload._buffer, static_cast<int>(env.payload._length))) {
    err.fault = DocumentFault::kUnparsable;
    err.message = where + "Protobuf could not parse " + std::to_string(env.payload._length) +
                  " bytes as " + expected.name;
    return err;
  }
  return std::nullopt;
}

DocumentWriter::DocumentWriter(Topic<smc_data_Envelope>& topic, Schema schema, bool per_machine)
    : topic_(&topic),
      writer_(topic),
      per_machine_(per_machine && topic.participant().options().machine.empty()),
      schema_(std::move(schema)) {}

WriterBase& DocumentWriter::writer_for(const std::string& key) {
  if (!per_machine_) return writer_;
  auto it = machines_.find(key);
  if (it == machines_.end())
    it = machines_.emplace(key, Writer<smc_data_Envelope>(*topic_, key)).first;
  return it->second;
}

void DocumentWriter::publish(std::string_view key, std::string_view document_id,
                             const google::protobuf::MessageLite& msg) {
  smc_data_Envelope env;
  encode_envelope(msg, schema_, key, document_id, ++sequence_, env);
  try {
    writer_for(std::string(key)).write_raw(&env);
  } catch (...) {
    free_envelope(env);
    throw;
  }
  free_envelope(env);
}

}  // namespace smc::transport
