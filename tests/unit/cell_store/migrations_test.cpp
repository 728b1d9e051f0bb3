// Opening: schema migrations, connection settings, refusing what is not ours.

#include <gmock/gmock.h>
#include <sqlite3.h>

#include "store_test_util.hpp"

namespace smc::cell::store::test {
namespace {

using ::testing::HasSubstr;

// Raw access to the file, as another program would have.
struct Raw {
  explicit Raw(const std::string& path) { EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK); }
  ~Raw() { sqlite3_close(db); }
  void exec(const std::string& sql) {
    char* err = nullptr;
    const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
    EXPECT_EQ(rc, SQLITE_OK) << sql << ": " << (err != nullptr ? err : "");
    sqlite3_free(err);
  }
  std::string text(const std::string& sql) {
    sqlite3_stmt* s = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr), SQLITE_OK) << sql;
    std::string out;
    if (sqlite3_step(s) == SQLITE_ROW && sqlite3_column_text(s, 0) != nullptr) {
      out = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    }
    sqlite3_finalize(s);
    return out;
  }
  sqlite3* db = nullptr;
};

class CellStoreMigrations : public StoreTest {};

TEST_F(CellStoreMigrations, FreshDatabaseIsAtTheLatestVersionInWalMode) {
  {
    Store s = Store::open(db_path());
    EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
    EXPECT_GE(Store::latest_schema_version(), 1);
    const Counts c = s.counts();
    EXPECT_EQ(c.machines + c.tools + c.materials + c.parts + c.models + c.jobs, 0);
  }
  Raw raw(db_path());
  EXPECT_EQ(raw.text("PRAGMA journal_mode"), "wal");
  EXPECT_EQ(raw.text("SELECT count(*) FROM schema_migrations"),
            std::to_string(Store::latest_schema_version()));
  EXPECT_EQ(raw.text("PRAGMA application_id"), "1397572419");
}

TEST_F(CellStoreMigrations, ReopeningChangesNothing) {
  { Store::open(db_path()); }
  std::string before;
  {
    Raw raw(db_path());
    before =
        raw.text("SELECT group_concat(version || ':' || applied_at_ms) FROM schema_migrations");
  }
  Store s = Store::open(db_path(), OpenMode::kExisting);
  EXPECT_EQ(s.schema_version(), Store::latest_schema_version());
  Raw raw(db_path());
  EXPECT_EQ(raw.text("SELECT group_concat(version || ':' || applied_at_ms) FROM schema_migrations"),
            before);
}

// A database of the version before (6: no machine channel) opened by this
// smc-cell gains the columns, and its machines keep their rows with the
// cell's default channel.
TEST_F(CellStoreMigrations, AnOlderDatabaseIsMigratedKeepingItsMachines) {
  {
    Store s = Store::open(db_path());
    s.put_machine(Machine{"mill-1", "the paper's mill", 745.7, 36, 3000});
  }
  {
    Raw raw(db_path());
    for (const char* c : {"wideband_samples_per_tick", "wideband_cutoff_hz",
                          "wideband_filter_order", "wideband_noise_rms_n"}) {
      raw.exec(std::string("ALTER TABLE machines DROP COLUMN ") + c);
    }
    raw.exec("DELETE FROM schema_migrations WHERE version = 7");
    ASSERT_EQ(raw.text("SELECT MAX(version) FROM schema_migrations"), "6");
  }
  Store s = Store::open(db_path(), OpenMode::kExisting);
  EXPECT_EQ(s.schema_version(), 7);
  const auto m = s.machine("mill-1");
  ASSERT_TRUE(m);
  EXPECT_DOUBLE_EQ(m->max_spindle_power_w, 745.7);
  EXPECT_TRUE(m->wideband.is_default());
  Machine with = *m;
  with.wideband = {.samples_per_tick = 1, .cutoff_hz = 500, .filter_order = 2};
  s.put_machine(with);
  EXPECT_EQ(s.machine("mill-1")->wideband.samples_per_tick, 1u);
  with.wideband.samples_per_tick = 9;
  EXPECT_THROW(s.put_machine(with), StoreError) << "the schema's CHECK holds too";
}

TEST_F(CellStoreMigrations, NewerDatabaseIsRefusedAndLeftUntouched) {
  { Store::open(db_path()); }
  const int newer = Store::latest_schema_version() + 1;
  {
    Raw raw(db_path());
    raw.exec("INSERT INTO schema_migrations VALUES (" + std::to_string(newer) + ", 'future', 0)");
  }
  try {
    Store::open(db_path());
    FAIL() << "a newer database was opened";
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr(db_path()));
    EXPECT_THAT(e.what(), HasSubstr("schema version " + std::to_string(newer) + " is newer"));
    EXPECT_THAT(e.what(), HasSubstr("fix:"));
  }
  Raw raw(db_path());
  EXPECT_EQ(raw.text("SELECT MAX(version) FROM schema_migrations"), std::to_string(newer));
}

TEST_F(CellStoreMigrations, MissingDatabaseIsAnErrorWhenItMustExist) {
  try {
    Store::open(db_path(), OpenMode::kExisting);
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr(db_path() + ": no such database"));
    EXPECT_THAT(e.what(), HasSubstr("smc-cell db init"));
  }
  EXPECT_FALSE(std::filesystem::exists(db_path()));
}

TEST_F(CellStoreMigrations, AFileThatIsNotADatabaseIsRefusedAndKept) {
  const std::string text = "plain text, not SQLite\n";
  const auto path = write("notes.db", text);
  try {
    Store::open(path);
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path));
    EXPECT_THAT(e.what(), HasSubstr("not a database"));
  }
  EXPECT_EQ(std::filesystem::file_size(path), text.size());
}

TEST_F(CellStoreMigrations, AnotherProgramsDatabaseIsRefused) {
  {
    Raw raw(db_path());
    raw.exec("CREATE TABLE invoices (id INTEGER)");
  }
  try {
    Store::open(db_path());
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not an smc-cell database"));
  }
  Raw raw(db_path());
  EXPECT_EQ(raw.text("SELECT count(*) FROM sqlite_schema WHERE name = 'jobs'"), "0");
}

TEST_F(CellStoreMigrations, StoresMoveAndSQLErrorsNameTheFile) {
  Store a = Store::open(db_path());
  Store b = std::move(a);
  EXPECT_EQ(b.path(), db_path());
  try {
    b.put_machine(Machine{"m", "bad", -1, 1, 1});  // CHECK constraint
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_THAT(e.what(), HasSubstr(db_path()));
    EXPECT_THAT(e.what(), HasSubstr("INSERT INTO machines"));
    EXPECT_THAT(e.what(), HasSubstr("CHECK constraint failed"));
  }
}

}  // namespace
}  // namespace smc::cell::store::test
