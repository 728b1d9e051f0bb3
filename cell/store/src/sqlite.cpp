#include "sqlite.hpp"

#include <chrono>
#include <limits>

namespace smc::cell::store::detail {

namespace {

// The SQL in an error message: whitespace collapsed, long scripts cut.
std::string one_line(std::string_view sql) {
  std::string out;
  bool space = false;
  for (const char c : sql) {
    if (c == ' ' || c == '\n' || c == '\t' || c == '\r') {
      space = !out.empty();
      continue;
    }
    if (space) out += ' ';
    space = false;
    out += c;
  }
  constexpr std::size_t kMax = 160;
  if (out.size() > kMax) out = out.substr(0, kMax) + "...";
  return out;
}

}  // namespace

void fail(sqlite3* db, const std::string& file, int rc, std::string_view what) {
  std::string msg = file + ": " + std::string(what) + ": ";
  const char* detail = db != nullptr ? sqlite3_errmsg(db) : nullptr;
  msg += detail != nullptr ? detail : sqlite3_errstr(rc);
  msg += " (" + std::string(sqlite3_errstr(rc)) + ", code " + std::to_string(rc) + ")";
  throw StoreError(msg);
}

void exec(sqlite3* db, const std::string& file, const char* sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    std::string msg = file + ": sqlite3_exec '" + one_line(sql) + "': ";
    msg += err != nullptr ? err : sqlite3_errstr(rc);
    sqlite3_free(err);
    throw StoreError(msg);
  }
}

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Stmt::Stmt(sqlite3* db, const std::string& file, std::string sql)
    : db_(db), file_(file), sql_(std::move(sql)) {
  const int rc = sqlite3_prepare_v2(db_, sql_.c_str(), -1, &stmt_, nullptr);
  if (rc != SQLITE_OK) {
    sqlite3_finalize(stmt_);
    stmt_ = nullptr;
    fail_here(rc, "sqlite3_prepare_v2");
  }
}

Stmt::~Stmt() { sqlite3_finalize(stmt_); }

void Stmt::fail_here(int rc, std::string_view call) const {
  fail(db_, file_, rc, std::string(call) + " '" + one_line(sql_) + "'");
}

void Stmt::bind_one(int i, std::int64_t v) {
  const int rc = sqlite3_bind_int64(stmt_, i, v);
  if (rc != SQLITE_OK) fail_here(rc, "sqlite3_bind_int64 #" + std::to_string(i));
}

void Stmt::bind_one(int i, double v) {
  const int rc = sqlite3_bind_double(stmt_, i, v);
  if (rc != SQLITE_OK) fail_here(rc, "sqlite3_bind_double #" + std::to_string(i));
}

void Stmt::bind_one(int i, const std::string& v) {
  const int rc = sqlite3_bind_text64(stmt_, i, v.data(), v.size(), SQLITE_TRANSIENT, SQLITE_UTF8);
  if (rc != SQLITE_OK) fail_here(rc, "sqlite3_bind_text64 #" + std::to_string(i));
}

void Stmt::bind_one(int i, const Blob& v) {
  const int rc = sqlite3_bind_blob64(stmt_, i, v.bytes.data(), v.bytes.size(), SQLITE_TRANSIENT);
  if (rc != SQLITE_OK) fail_here(rc, "sqlite3_bind_blob64 #" + std::to_string(i));
}

void Stmt::bind_one(int i, Null) {
  const int rc = sqlite3_bind_null(stmt_, i);
  if (rc != SQLITE_OK) fail_here(rc, "sqlite3_bind_null #" + std::to_string(i));
}

bool Stmt::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  fail_here(rc, "sqlite3_step");
}

void Stmt::run() {
  if (step()) fail_here(SQLITE_MISUSE, "sqlite3_step (a statement meant to return no rows)");
}

void Stmt::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

bool Stmt::is_null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
std::int64_t Stmt::int64(int col) const { return sqlite3_column_int64(stmt_, col); }
double Stmt::real(int col) const { return sqlite3_column_double(stmt_, col); }

std::string Stmt::text(int col) const {
  const auto* p = sqlite3_column_text(stmt_, col);
  const int n = sqlite3_column_bytes(stmt_, col);
  if (p == nullptr || n <= 0) return {};
  return std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(n));
}

std::string Stmt::blob(int col) const {
  const void* p = sqlite3_column_blob(stmt_, col);
  const int n = sqlite3_column_bytes(stmt_, col);
  if (p == nullptr || n <= 0) return {};
  return std::string(static_cast<const char*>(p), static_cast<std::size_t>(n));
}

Tx::Tx(sqlite3* db, const std::string& file)
    : db_(db), file_(file), nested_(sqlite3_get_autocommit(db) == 0) {
  exec(db_, file_, nested_ ? "SAVEPOINT smc_nested" : "BEGIN IMMEDIATE");
}

Tx::~Tx() {
  if (done_) return;
  // Never throws: a failed rollback leaves SQLite to roll back on close.
  if (nested_) {
    sqlite3_exec(db_, "ROLLBACK TO smc_nested; RELEASE smc_nested", nullptr, nullptr, nullptr);
  } else if (sqlite3_get_autocommit(db_) == 0) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
}

void Tx::commit() {
  exec(db_, file_, nested_ ? "RELEASE smc_nested" : "COMMIT");
  done_ = true;
}

std::string serialize(const google::protobuf::MessageLite& msg, std::string_view what) {
  std::string out;
  if (!msg.SerializeToString(&out)) {
    throw StoreError("cannot serialize " + std::string(what) + " (" + msg.GetTypeName() + ")");
  }
  return out;
}

void deserialize(const std::string& bytes, google::protobuf::MessageLite& msg,
                 const std::string& file, std::string_view what) {
  if (!msg.ParseFromString(bytes)) {
    throw StoreError(file + ": " + std::string(what) + ": stored " + msg.GetTypeName() +
                     " does not parse (database damaged or written by another program)");
  }
}

}  // namespace smc::cell::store::detail
