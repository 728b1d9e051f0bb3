#pragma once
// A small streaming JSON writer for the data-plane events (the Protobuf
// documents go through Protobuf's own JSON mapping instead). Commas are
// placed automatically; numbers that are not finite are written as null;
// 64-bit integers that a browser cannot hold exactly go through string().

#include <concepts>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace smc::dashboard {

// Appends `s` as a quoted JSON string (UTF-8 passed through; control
// characters, quote and backslash escaped).
void append_json_string(std::string& out, std::string_view s);

class JsonWriter {
 public:
  JsonWriter& begin_object();
  JsonWriter& end_object();
  JsonWriter& begin_array();
  JsonWriter& end_array();
  JsonWriter& key(std::string_view k);

  JsonWriter& value(std::string_view s);
  JsonWriter& value(const char* s) { return value(std::string_view(s)); }
  JsonWriter& value(const std::string& s) { return value(std::string_view(s)); }
  JsonWriter& value(bool b);
  JsonWriter& value(double d);
  JsonWriter& value(float f);  // shortest form that reads back as the same float
  template <std::integral T>
  requires(!std::same_as<T, bool>) JsonWriter& value(T v) {
    separate();
    out_ += std::to_string(v);
    return *this;
  }
  JsonWriter& null();
  // A value that is already JSON (e.g. Protobuf's JSON mapping of a document).
  JsonWriter& raw(std::string_view json);

  template <class T>
  JsonWriter& field(std::string_view k, const T& v) {
    key(k);
    return value(v);
  }

  const std::string& str() const noexcept { return out_; }
  std::string take() { return std::move(out_); }

 private:
  void separate();
  std::string out_;
  std::vector<bool> has_items_;  // per open container
  bool after_key_ = false;
};

}  // namespace smc::dashboard
