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

class Collector final : public google::protobuf::io::ErrorCollector {
 public:
  explicit Collector(std::string name) : name_(std::move(name)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    out_ << name_ << ":" << line + 1 << ":" << column + 1 << ": " << message << "\n";
  }
  void AddWarning(int line, google::protobuf::io::ColumnNumber column,
                  const std::string& message) override {
    AddError(line, column, "warning: " + message);
  }
  std::string text() const { return out_.str(); }

 private:
  std::string name_;
  std::ostringstream out_;
};

bool is_json(const std::string& path) { return std::filesystem::path(path).extension() == ".json"; }

}  // namespace

std::string read_file(const std::string& path) {
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
      throw DocumentError(name + ": not a valid " + msg.GetTypeName() +
                          " in JSON: " + std::string(st.message()));
    }
    return;
  }
  Collector errors(name);
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &msg)) {
    std::string e = errors.text();
    if (!e.empty() && e.back() == '\n') e.pop_back();
    throw DocumentError(e.empty() ? name + ": not a valid " + msg.GetTypeName() : e);
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
