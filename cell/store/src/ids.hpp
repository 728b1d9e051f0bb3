#pragma once
// Private helpers shared by the catalog and the jobs: id lists for error
// messages, and generated ids.

#include <sqlite3.h>

#include <string>
#include <string_view>
#include <vector>

namespace smc::cell::store::detail {

// The first column of every row of `sql` (e.g. "SELECT id FROM parts ORDER BY id").
std::vector<std::string> ids(sqlite3* db, const std::string& file, const char* sql);
// "unknown part 'x' (known: a, b)"
std::string unknown_ref(std::string_view what, const std::string& value,
                        const std::vector<std::string>& known);
// "<series>-000042": the next number of the series, skipping ids `exists_sql`
// (one ? parameter) finds. Call inside a write transaction.
std::string next_id(sqlite3* db, const std::string& file, const std::string& series,
                    const char* exists_sql);

}  // namespace smc::cell::store::detail
