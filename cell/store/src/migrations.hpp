#pragma once
// Private: the schema migrations (migrations.cpp).

#include <sqlite3.h>

#include <cstdint>
#include <span>
#include <string>

namespace smc::cell::store::detail {

struct Migration {
  int version;
  const char* description;
  const char* sql;  // a fixed script: no values
};

std::span<const Migration> migrations() noexcept;
// Applies every migration the database lacks, in order, one transaction
// each. StoreError when the database is newer than the code.
void migrate(sqlite3* db, const std::string& file);
[[noreturn]] void throw_newer(const std::string& file, std::int64_t found, int latest);

}  // namespace smc::cell::store::detail
