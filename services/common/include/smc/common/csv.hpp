#pragma once
// Writing CSV files (RFC 4180: comma-separated, "quoted" when a field holds a
// comma, quote or line break; numbers with 10 significant digits, NaN empty).

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace smc::csv {

// Row by row:
//   Writer w("out.csv", {"time_s", "fy_n"});
//   w.row({0.0005, -12.5});
//   w.close();
class Writer {
 public:
  // Opens (truncates) the file and writes the header. Throws
  // std::runtime_error "FILE: cannot open for writing: reason".
  Writer(const std::filesystem::path& file, const std::vector<std::string>& header);
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  ~Writer();

  // One field at a time, then end_row().
  Writer& field(double value);
  Writer& field(long long value);
  Writer& field(std::string_view text);
  void end_row();
  // A whole row of numbers.
  void row(const std::vector<double>& values);
  // Flushes and closes; throws std::runtime_error if anything failed.
  void close();

 private:
  void separator();
  std::filesystem::path path_;
  std::ofstream out_;
  bool row_started_ = false;
  bool closed_ = false;
};

// Columns of equal length under a header (throws std::invalid_argument if the
// lengths differ or the header does not match the column count).
void write_columns(const std::filesystem::path& file, const std::vector<std::string>& header,
                   const std::vector<const std::vector<double>*>& columns);

// A field as it appears in a file (quoted if needed).
std::string quote(std::string_view text);
std::string format_number(double value);

}  // namespace smc::csv
