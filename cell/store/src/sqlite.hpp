#pragma once
// Private: the thin layer over the SQLite C API. Every return code goes
// through check()/fail(), which raise StoreError naming the database file,
// the call and its SQL. Values reach SQL only as bound parameters.

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "smc/cell/store/store.hpp"

namespace smc::cell::store::detail {

[[noreturn]] void fail(sqlite3* db, const std::string& file, int rc, std::string_view what);
inline void check(sqlite3* db, const std::string& file, int rc, std::string_view what) {
  if (rc != SQLITE_OK) fail(db, file, rc, what);
}
// Runs a fixed SQL script (no values in it) with sqlite3_exec.
void exec(sqlite3* db, const std::string& file, const char* sql);

std::int64_t now_ms();

// Bytes for a BLOB parameter or column (distinct from TEXT).
struct Blob {
  std::string bytes;
};
struct Null {};
// An empty string as NULL (optional references: part_id, tool_id, machine_id).
inline std::optional<std::string> or_null(const std::string& s) {
  return s.empty() ? std::nullopt : std::optional<std::string>(s);
}

// One prepared statement. Bind with bind(v1, v2, ...) (positions 1, 2, ...),
// then step() for each row, or run() for a statement that returns none.
class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& file, std::string sql);
  ~Stmt();
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  template <class... Args>
  Stmt& bind(const Args&... args) {
    int i = 0;
    (bind_one(++i, args), ...);
    return *this;
  }
  bool step();   // true: a row is ready; false: done
  void run();    // steps to the end; a returned row is an error
  void reset();  // ready to bind and run again (bindings cleared)

  bool is_null(int col) const;
  std::int64_t int64(int col) const;
  double real(int col) const;
  std::string text(int col) const;
  std::string blob(int col) const;

 private:
  void bind_one(int i, std::int64_t v);
  void bind_one(int i, int v) { bind_one(i, static_cast<std::int64_t>(v)); }
  void bind_one(int i, std::uint32_t v) { bind_one(i, static_cast<std::int64_t>(v)); }
  void bind_one(int i, bool v) { bind_one(i, static_cast<std::int64_t>(v ? 1 : 0)); }
  void bind_one(int i, double v);
  void bind_one(int i, const std::string& v);
  void bind_one(int i, const char* v) { bind_one(i, std::string(v)); }
  void bind_one(int i, const Blob& v);
  void bind_one(int i, Null);
  template <class T>
  void bind_one(int i, const std::optional<T>& v) {
    if (v) {
      bind_one(i, *v);
    } else {
      bind_one(i, Null{});
    }
  }
  [[noreturn]] void fail_here(int rc, std::string_view call) const;

  sqlite3* db_;
  const std::string& file_;
  std::string sql_;
  sqlite3_stmt* stmt_ = nullptr;
};

// A write transaction: BEGIN IMMEDIATE at the outermost level (the write
// lock is taken at once, so two writers queue on the busy timeout instead of
// failing on upgrade), a SAVEPOINT when nested. Rolls back unless committed.
class Tx {
 public:
  Tx(sqlite3* db, const std::string& file);
  ~Tx();
  Tx(const Tx&) = delete;
  Tx& operator=(const Tx&) = delete;
  void commit();

 private:
  sqlite3* db_;
  const std::string& file_;
  bool nested_;
  bool done_ = false;
};

// Serializes a message; StoreError when it cannot be.
std::string serialize(const google::protobuf::MessageLite& msg, std::string_view what);
// Parses a stored document; StoreError naming the row when it does not parse.
void deserialize(const std::string& bytes, google::protobuf::MessageLite& msg,
                 const std::string& file, std::string_view what);

}  // namespace smc::cell::store::detail
