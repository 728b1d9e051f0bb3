#include "smc/documents/load.hpp"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

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

// Protobuf's JSON parser lets the last of two equal keys win silently; a
// document with a duplicate key is refused instead, naming both places.
// A small scan over the text: strings (with escapes), objects and arrays;
// the key set of every open object. Malformed JSON is left to the parser.
void check_duplicate_keys(const std::string& text, const std::string& name,
                          common::Diagnostics& problems) {
  struct Object {
    std::map<std::string, std::pair<int, int>> keys;  // key -> line, column
    bool expect_key = true;
  };
  std::vector<Object> open;  // objects only; arrays push a marker-less frame below
  std::vector<char> nest;
  int line = 1, col = 1;
  for (std::size_t i = 0; i < text.size(); ++i, ++col) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      col = 0;
      continue;
    }
    if (c == '{') {
      nest.push_back('{');
      open.emplace_back();
    } else if (c == '[') {
      nest.push_back('[');
    } else if (c == '}' || c == ']') {
      if (nest.empty()) return;
      if (nest.back() == '{' && !open.empty()) open.pop_back();
      nest.pop_back();
    } else if (c == ',') {
      if (!nest.empty() && nest.back() == '{' && !open.empty()) open.back().expect_key = true;
    } else if (c == '"') {
      const int l = line, k = col;
      std::string s;
      for (++i, ++col; i < text.size() && text[i] != '"'; ++i, ++col) {
        if (text[i] == '\\' && i + 1 < text.size()) {
          s += text[++i];
          ++col;
        } else {
          s += text[i];
        }
      }
      if (!nest.empty() && nest.back() == '{' && !open.empty() && open.back().expect_key) {
        open.back().expect_key = false;
        auto [it, fresh] = open.back().keys.emplace(s, std::pair{l, k});
        if (!fresh) {
          problems.add(name + ":" + std::to_string(l) + ":" + std::to_string(k),
                       "duplicate key " + common::quote(s) + " (first at line " +
                           std::to_string(it->second.first) + ")",
                       "give each field once; JSON readers disagree on which copy wins");
        }
      }
    }
  }
}

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
    common::Diagnostics duplicates;
    check_duplicate_keys(text, name, duplicates);
    if (!duplicates.ok()) throw DocumentError(std::move(duplicates));
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
