#include "smc/common/csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace smc::csv {

std::string quote(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string format_number(double value) {
  if (!std::isfinite(value)) return {};
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", value);
  return buf;
}

Writer::Writer(const std::filesystem::path& file, const std::vector<std::string>& header)
    : path_(file), out_(file, std::ios::binary | std::ios::trunc) {
  if (!out_) {
    throw std::runtime_error(file.string() + ": cannot open for writing: " + std::strerror(errno));
  }
  for (const std::string& h : header) field(h);
  end_row();
}

Writer::~Writer() {
  if (!closed_) out_.close();  // errors here are reported only by close()
}

void Writer::separator() {
  if (row_started_) out_ << ',';
  row_started_ = true;
}

Writer& Writer::field(double value) {
  separator();
  out_ << format_number(value);
  return *this;
}

Writer& Writer::field(long long value) {
  separator();
  out_ << value;
  return *this;
}

Writer& Writer::field(std::string_view text) {
  separator();
  out_ << quote(text);
  return *this;
}

void Writer::end_row() {
  out_ << '\n';
  row_started_ = false;
}

void Writer::row(const std::vector<double>& values) {
  for (const double v : values) field(v);
  end_row();
}

void Writer::close() {
  if (closed_) return;
  closed_ = true;
  out_.close();
  if (!out_) throw std::runtime_error(path_.string() + ": cannot write");
}

void write_columns(const std::filesystem::path& file, const std::vector<std::string>& header,
                   const std::vector<const std::vector<double>*>& columns) {
  if (header.size() != columns.size()) {
    throw std::invalid_argument("csv::write_columns: " + std::to_string(header.size()) +
                                " headers for " + std::to_string(columns.size()) + " columns");
  }
  const std::size_t rows = columns.empty() ? 0 : columns.front()->size();
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c]->size() != rows) {
      throw std::invalid_argument("csv::write_columns: column '" + header[c] + "' has " +
                                  std::to_string(columns[c]->size()) + " rows, expected " +
                                  std::to_string(rows));
    }
  }
  Writer w(file, header);
  for (std::size_t r = 0; r < rows; ++r) {
    for (const auto* col : columns) w.field((*col)[r]);
    w.end_row();
  }
  w.close();
}

}  // namespace smc::csv
