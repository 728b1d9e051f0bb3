// Opening the database: connection settings, ownership check, migrations.

#include "smc/cell/store/store.hpp"

#include <cstdlib>
#include <filesystem>
#include <string_view>

#include "migrations.hpp"
#include "sqlite.hpp"

namespace smc::cell::store {

using detail::Stmt;

namespace {

constexpr std::int64_t kApplicationId = 1397572419;  // 'SMCC', set by migration 1
constexpr int kBusyTimeoutMs = 10000;                // a CLI and the service share the file

std::string pragma_text(sqlite3* db, const std::string& file, const char* sql) {
  Stmt s(db, file, sql);
  return s.step() ? s.text(0) : std::string();
}

std::int64_t pragma_int(sqlite3* db, const std::string& file, const char* sql) {
  Stmt s(db, file, sql);
  return s.step() ? s.int64(0) : 0;
}

bool has_table(sqlite3* db, const std::string& file, const std::string& name) {
  Stmt s(db, file, "SELECT 1 FROM sqlite_schema WHERE type = 'table' AND name = ?");
  return s.bind(name).step();
}

}  // namespace

namespace {
std::string join_errors(const std::vector<FieldError>& errors) {
  std::string s;
  for (const auto& e : errors) {
    if (!s.empty()) s += '\n';
    s += e.str();
  }
  return s;
}
}  // namespace

JobRejected::JobRejected(std::vector<FieldError> errs)
    : StoreError(join_errors(errs)), errors(std::move(errs)) {}

std::string default_db_path() {
  const char* env = std::getenv("SMC_CELL_DB");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string("smc-cell.db");
}

void Store::Close::operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }

Store::Store(std::string path, sqlite3* db) noexcept : path_(std::move(path)), db_(db) {}
Store::Store(Store&&) noexcept = default;
Store& Store::operator=(Store&&) noexcept = default;
Store::~Store() = default;

int Store::latest_schema_version() noexcept { return detail::migrations().back().version; }

Store Store::open(const std::string& path, OpenMode mode) {
  if (path.empty()) throw StoreError("Store::open: empty database path; fix: give --db FILE");
  if (mode == OpenMode::kExisting && path != ":memory:" && !std::filesystem::exists(path)) {
    throw StoreError(path + ": no such database; fix: create it with 'smc-cell db init --db " +
                     path + " --seed', or point --db / $SMC_CELL_DB at the cell's database");
  }
  sqlite3* raw = nullptr;
  int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX;
  if (mode == OpenMode::kCreate) flags |= SQLITE_OPEN_CREATE;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  // Owned from here on, even when opening failed.
  Store store(path, raw);
  if (rc != SQLITE_OK) detail::fail(raw, path, rc, "sqlite3_open_v2");
  sqlite3* db = raw;
  sqlite3_extended_result_codes(db, 1);
  detail::check(db, path, sqlite3_busy_timeout(db, kBusyTimeoutMs), "sqlite3_busy_timeout");

  // The first read: a file that is not SQLite fails here ("file is not a database").
  const std::int64_t app_id = pragma_int(db, path, "PRAGMA application_id");
  const bool ours = has_table(db, path, "schema_migrations");
  if ((app_id != 0 && app_id != kApplicationId) ||
      (app_id == 0 && !ours && pragma_int(db, path, "SELECT count(*) FROM sqlite_schema") > 0)) {
    throw StoreError(path + ": not an smc-cell database (application_id " + std::to_string(app_id) +
                     ", no schema_migrations); fix: choose another file for --db");
  }
  const int latest = latest_schema_version();
  std::int64_t version = 0;
  if (ours) {
    version = pragma_int(db, path, "SELECT COALESCE(MAX(version), 0) FROM schema_migrations");
    if (version > latest) detail::throw_newer(path, version, latest);
  }

  // Durability and sharing: WAL lets the CLI read while the service writes;
  // synchronous=FULL syncs the WAL at every commit, so an accepted job is on
  // disk when submit_job returns, whatever happens to the process next.
  const std::string journal = pragma_text(db, path, "PRAGMA journal_mode = WAL");
  if (journal != "wal" && path != ":memory:") {
    throw StoreError(path + ": PRAGMA journal_mode = WAL: the database stays in '" + journal +
                     "' mode; fix: put the database on a local file system");
  }
  detail::exec(db, path, "PRAGMA synchronous = FULL");
  detail::exec(db, path, "PRAGMA foreign_keys = ON");
  if (pragma_int(db, path, "PRAGMA foreign_keys") != 1) {
    throw StoreError(path + ": PRAGMA foreign_keys = ON: not supported by this SQLite build");
  }
  if (version < latest) detail::migrate(db, path);
  return store;
}

int Store::schema_version() {
  Stmt s(db_.get(), path_, "SELECT COALESCE(MAX(version), 0) FROM schema_migrations");
  s.step();
  return static_cast<int>(s.int64(0));
}

std::int64_t Store::data_version() { return pragma_int(db_.get(), path_, "PRAGMA data_version"); }

void Store::transaction(const std::function<void()>& body) {
  detail::Tx tx(db_.get(), path_);
  body();
  tx.commit();
}

Counts Store::counts() {
  Counts c;
  // One read transaction, so the counts are of one moment.
  const bool own = sqlite3_get_autocommit(db_.get()) != 0;
  if (own) detail::exec(db_.get(), path_, "BEGIN DEFERRED");
  try {
    const auto count = [&](const char* sql) {
      Stmt s(db_.get(), path_, sql);
      s.step();
      return s.int64(0);
    };
    c.machines = count("SELECT count(*) FROM machines");
    c.tools = count("SELECT count(*) FROM tools");
    c.materials = count("SELECT count(*) FROM materials");
    c.parts = count("SELECT count(*) FROM parts");
    c.models = count("SELECT count(*) FROM process_models");
    c.jobs = count("SELECT count(*) FROM jobs");
    c.job_events = count("SELECT count(*) FROM job_events");
    Stmt s(db_.get(), path_, "SELECT state, count(*) FROM jobs GROUP BY state ORDER BY state");
    while (s.step()) {
      c.jobs_by_state.emplace_back(static_cast<smc::config::JobState>(s.int64(0)), s.int64(1));
    }
  } catch (...) {
    if (own) sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  if (own) detail::exec(db_.get(), path_, "COMMIT");
  return c;
}

}  // namespace smc::cell::store
