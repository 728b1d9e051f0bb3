#include "smc/documents/load.hpp"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "smc_config.pb.h"

namespace smc::documents {

namespace {

// Protobuf's messages can quote the offending text: keep each one bounded.
std::string bounded(const std::string& message) {
  constexpr std::size_t kMax = 240;
  if (message.size() <= kMax) return message;
  return message.substr(0, kMax) + "…(" + std::to_string(message.size()) + " bytes)";
}

class Collector final : public google::protobuf::io::ErrorCollector {
 public:
  explicit Collector(std::string name) : name_(std::move(name)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    problems_.add(name_ + ":" + std::to_string(line + 1) + ":" + std::to_string(column + 1),
                  bounded(message));
  }
  void AddWarning(int line, google::protobuf::io::ColumnNumber column,
                  const std::string& message) override {
    AddError(line, column, "warning: " + message);
  }
  common::Diagnostics& problems() { return problems_; }

 private:
  std::string name_;
  common::Diagnostics problems_;
};

bool is_json(const std::string& path) { return std::filesystem::path(path).extension() == ".json"; }

}  // namespace

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw DocumentError(
        common::Diagnostic{path, "is a folder, not a document", "give a .textproto or .json file"});
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DocumentError(path + ": cannot open (" + std::string(std::strerror(errno)) + ")");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void parse(const std::string& text, bool json, const std::string& name,
           google::protobuf::Message& msg) {
  if (json) {
    google::protobuf::util::JsonParseOptions opts;
    opts.ignore_unknown_fields = false;
    const auto st = google::protobuf::util::JsonStringToMessage(text, &msg, opts);
    if (!st.ok()) {
      throw DocumentError(common::Diagnostic{
          name,
          "not a valid " + msg.GetTypeName() + " in JSON: " + bounded(std::string(st.message())),
          ""});
    }
    return;
  }
  Collector errors(name);
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &msg)) {
    if (errors.problems().empty()) errors.problems().add(name, "not a valid " + msg.GetTypeName());
    throw DocumentError(std::move(errors.problems()));
  }
}

void load(const std::string& path, google::protobuf::Message& msg) {
  parse(read_file(path), is_json(path), path, msg);
}

std::string to_json(const google::protobuf::Message& msg, bool pretty) {
  google::protobuf::util::JsonPrintOptions opts;
  opts.add_whitespace = pretty;
  opts.preserve_proto_field_names = true;
  opts.always_print_primitive_fields = true;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(msg, &out, opts);
  return out;
}

std::string to_textproto(const google::protobuf::Message& msg) {
  std::string out;
  google::protobuf::TextFormat::PrintToString(msg, &out);
  return out;
}

smc::config::SupervisorConfig load_supervisor_config(const std::string& path) {
  smc::config::SupervisorConfig cfg;
  load(path, cfg);
  const auto dir = std::filesystem::path(path).parent_path();
  if (!cfg.grafcet_file().empty()) {
    const auto g = (dir / cfg.grafcet_file()).lexically_normal().string();
    try {
      cfg.set_grafcet_text(read_file(g));
    } catch (const DocumentError& e) {
      throw DocumentError(path + ": grafcet_file: " + e.what());
    }
    if (cfg.grafcet_name().empty()) cfg.set_grafcet_name(g);
    cfg.clear_grafcet_file();
  }
  if (!cfg.milling_model_file().empty()) {
    const auto m = (dir / cfg.milling_model_file()).lexically_normal().string();
    try {
      load(m, *cfg.mutable_milling_model());
    } catch (const DocumentError& e) {
      throw DocumentError(path + ": milling_model_file: " + e.what());
    }
    cfg.clear_milling_model_file();
  }
  return cfg;
}

}  // namespace smc::documents
