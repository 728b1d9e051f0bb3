#pragma once
// Reading and writing the configuration-plane documents (idl/smc_config.proto)
// as text: textproto (.textproto, .txtpb, .pbtxt) or JSON (.json), chosen by
// the file's extension. Errors name file:line:col and what is wrong.

#include <stdexcept>
#include <string>

#include "smc/common/diagnostic.hpp"

namespace google::protobuf {
class Message;
}
namespace smc::config {
class SupervisorConfig;
}

namespace smc::documents {

// A document that cannot be used: every problem as a diagnostic ("path:line:col"
// or "path" and what is wrong), at most 20 of them printed ("and K more"),
// values quoted and cut so a huge field is never echoed whole.
struct DocumentError : common::DiagnosticError {
  using common::DiagnosticError::DiagnosticError;
  explicit DocumentError(const std::string& message)
      : common::DiagnosticError(common::Diagnostic{"", message, ""}) {}
};

// Parses `path` into `msg`. Unknown fields are errors. Throws DocumentError
// with every problem found, one per line, as "path:line:col: message".
void load(const std::string& path, google::protobuf::Message& msg);
// Parses text (textproto, or JSON when `json`) with `name` in messages.
void parse(const std::string& text, bool json, const std::string& name,
           google::protobuf::Message& msg);

// Serializes as JSON (Protobuf's JSON mapping) or textproto.
std::string to_json(const google::protobuf::Message& msg, bool pretty = true);
std::string to_textproto(const google::protobuf::Message& msg);

// Reads a SupervisorConfig and resolves grafcet_file and milling_model_file
// relative to the file's folder into grafcet_text and milling_model.
smc::config::SupervisorConfig load_supervisor_config(const std::string& path);

// The whole text of a file; DocumentError naming it when unreadable.
std::string read_file(const std::string& path);

}  // namespace smc::documents
