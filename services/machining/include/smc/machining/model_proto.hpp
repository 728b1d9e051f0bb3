#pragma once
// Conversions between the configuration documents (idl/smc_config.proto) and
// the plain model structs, and loading a model document from a file. The
// proto classes are only forward-declared here: include the generated
// smc_config.pb.h where you build or read the messages.

#include <filesystem>
#include <string>

#include "smc/machining/force_process.hpp"
#include "smc/machining/model.hpp"

namespace smc::config {
class MillingModel;
class ForceProcessModel;
}  // namespace smc::config

namespace smc::machining {

// Converts and validates. Unset proto fields are zero: every field the model
// relies on must be set. internal_step_s == 0 means the library default
// (1e-5 s), delay UNSPECIFIED means the tooth period. Throws ModelError naming
// every bad field with `prefix` as the root of the path, for example
// "milling_model.structure.tool_x[0].damping_ratio: must be in (0, 1), got 1.7".
MillingModel from_proto(const smc::config::MillingModel& message,
                        const std::string& prefix = "milling_model");
smc::config::MillingModel to_proto(const MillingModel& model);

// Eq. (1): converts and validates (k_kn > 0; exponents finite). Throws
// ModelError with paths under `prefix`.
ForceProcessModel from_proto(const smc::config::ForceProcessModel& message,
                             const std::string& prefix = "force_model");
smc::config::ForceProcessModel to_proto(const ForceProcessModel& model);

// Reads a smc.config.MillingModel document: JSON (Protobuf's JSON mapping)
// when the extension is .json, text format otherwise (.textproto, .txtpb,
// .pbtxt). Throws std::runtime_error "FILE:LINE:COL: message" on a syntax
// error, and ModelError "FILE: milling_model.FIELD: ..." for bad values.
MillingModel load_milling_model(const std::filesystem::path& file);
ForceProcessModel load_force_process_model(const std::filesystem::path& file);

// Parses a document already in memory (`name` is used in messages).
MillingModel parse_milling_model(const std::string& text, bool json, const std::string& name);
ForceProcessModel parse_force_process_model(const std::string& text, bool json,
                                            const std::string& name);

}  // namespace smc::machining
