// The schema, as an ordered list of migrations. Policy (README.md): a
// migration, once released, is never edited; a change is a new migration
// appended at the end. Each runs in its own transaction together with its
// row in schema_migrations.

#include "migrations.hpp"

#include <array>

#include "sqlite.hpp"

namespace smc::cell::store::detail {

namespace {

constexpr std::array kMigrations{
    Migration{1, "catalog, process models, jobs and job events", R"sql(
PRAGMA application_id = 1397572419;  -- 'SMCC': refuse to open a foreign database

CREATE TABLE machines (
  id                  TEXT PRIMARY KEY NOT NULL,
  name                TEXT NOT NULL,
  max_spindle_power_w REAL NOT NULL CHECK (max_spindle_power_w > 0),
  max_feedrate_mm_s   REAL NOT NULL CHECK (max_feedrate_mm_s > 0),
  max_spindle_rpm     REAL NOT NULL CHECK (max_spindle_rpm > 0)
);

CREATE TABLE tools (
  id             TEXT PRIMARY KEY NOT NULL,
  name           TEXT NOT NULL,
  teeth          INTEGER NOT NULL CHECK (teeth > 0),
  radius_mm      REAL NOT NULL CHECK (radius_mm > 0),
  lead_angle_deg REAL NOT NULL CHECK (lead_angle_deg >= 0 AND lead_angle_deg < 90)
);

CREATE TABLE materials (
  id   TEXT PRIMARY KEY NOT NULL,
  name TEXT NOT NULL
);

CREATE TABLE parts (
  id             TEXT PRIMARY KEY NOT NULL,
  name           TEXT NOT NULL,
  material_id    TEXT NOT NULL REFERENCES materials (id),
  tool_id        TEXT REFERENCES tools (id),
  width_mm       REAL NOT NULL CHECK (width_mm > 0),
  offset_mm      REAL NOT NULL,
  length_mm      REAL NOT NULL CHECK (length_mm > 0),
  total_depth_mm REAL NOT NULL CHECK (total_depth_mm > 0),
  feedrate_mm_s  REAL NOT NULL CHECK (feedrate_mm_s > 0),
  spindle_rpm    REAL NOT NULL CHECK (spindle_rpm > 0)
);

-- kind 1: smc.config.ForceProcessModel, 2: smc.config.MillingModel.
-- provenance: smc.config.Provenance. part_id NULL: any part of the material.
CREATE TABLE process_models (
  id            TEXT PRIMARY KEY NOT NULL,
  kind          INTEGER NOT NULL CHECK (kind IN (1, 2)),
  machine_id    TEXT NOT NULL REFERENCES machines (id),
  tool_id       TEXT NOT NULL REFERENCES tools (id),
  material_id   TEXT NOT NULL REFERENCES materials (id),
  part_id       TEXT REFERENCES parts (id),
  provenance    INTEGER NOT NULL CHECK (provenance BETWEEN 0 AND 3),
  validated     INTEGER NOT NULL CHECK (validated IN (0, 1)),
  document      BLOB NOT NULL,
  fit           BLOB,
  note          TEXT NOT NULL DEFAULT '',
  created_at_ms INTEGER NOT NULL
);
CREATE INDEX process_models_by_use ON process_models (material_id, part_id, machine_id, tool_id);

-- state, variant: smc.config.JobState, smc.config.SmcVariant.
-- spec: smc.config.Job; plan: smc.config.SupervisorConfig; result:
-- smc.config.RunSummary. seq is AUTOINCREMENT: never reused.
CREATE TABLE jobs (
  seq           INTEGER PRIMARY KEY AUTOINCREMENT,
  id            TEXT NOT NULL UNIQUE,
  spec          BLOB NOT NULL,
  part_id       TEXT NOT NULL REFERENCES parts (id),
  state         INTEGER NOT NULL CHECK (state BETWEEN 1 AND 7),
  machine_id    TEXT REFERENCES machines (id),
  variant       INTEGER NOT NULL DEFAULT 0,
  explanation   TEXT NOT NULL DEFAULT '',
  plan          BLOB,
  result        BLOB,
  attempt       INTEGER NOT NULL DEFAULT 0 CHECK (attempt >= 0),
  created_at_ms INTEGER NOT NULL,
  updated_at_ms INTEGER NOT NULL
);
CREATE INDEX jobs_by_state ON jobs (state, seq);

-- from_state 0 (unspecified): the submission.
CREATE TABLE job_events (
  job_id     TEXT NOT NULL REFERENCES jobs (id),
  seq        INTEGER NOT NULL CHECK (seq > 0),
  time_ms    INTEGER NOT NULL,
  from_state INTEGER NOT NULL,
  to_state   INTEGER NOT NULL,
  reason     TEXT NOT NULL,
  machine_id TEXT,
  PRIMARY KEY (job_id, seq)
) WITHOUT ROWID;

-- Accepted jobs and their history are never edited away.
CREATE TRIGGER jobs_never_deleted BEFORE DELETE ON jobs
BEGIN SELECT RAISE(ABORT, 'jobs are never deleted'); END;
CREATE TRIGGER job_events_append_only_update BEFORE UPDATE ON job_events
BEGIN SELECT RAISE(ABORT, 'job_events are append-only'); END;
CREATE TRIGGER job_events_append_only_delete BEFORE DELETE ON job_events
BEGIN SELECT RAISE(ABORT, 'job_events are append-only'); END;

-- Last number handed out per id series ("job", "model"); only ever grows.
CREATE TABLE id_counters (
  name TEXT PRIMARY KEY NOT NULL,
  last INTEGER NOT NULL
) WITHOUT ROWID;
)sql"},
    Migration{2, "plans bound to a machine and its models; models marked suspect", R"sql(
-- planned_for: the machine whose models an SMC I plan used (dispatch sends
-- the job only there); NULL when the plan suits any machine (SMC II).
ALTER TABLE jobs ADD COLUMN planned_for TEXT REFERENCES machines (id);

-- The models a job's current plan was made from (replaced by a re-plan).
CREATE TABLE job_plan_models (
  job_id   TEXT NOT NULL REFERENCES jobs (id),
  model_id TEXT NOT NULL REFERENCES process_models (id),
  PRIMARY KEY (job_id, model_id)
) WITHOUT ROWID;

-- Non-empty: the model is suspect (e.g. a cut planned from it chattered)
-- and is not used for SMC I until it is validated again.
ALTER TABLE process_models ADD COLUMN suspect_reason TEXT NOT NULL DEFAULT '';
)sql"},
    Migration{
        3, "catalog documents: machine speed range and drive, retirement, model validity, history",
        R"sql(
ALTER TABLE machines ADD COLUMN min_spindle_rpm REAL NOT NULL DEFAULT 0;
ALTER TABLE machines ADD COLUMN drive TEXT NOT NULL DEFAULT 'simulated';
-- retired_at_ms: NULL = in use. Nothing a job used is ever deleted; retired
-- entities stay for the record and are refused by new jobs.
ALTER TABLE machines ADD COLUMN retired_at_ms INTEGER;
ALTER TABLE tools ADD COLUMN retired_at_ms INTEGER;
ALTER TABLE materials ADD COLUMN retired_at_ms INTEGER;
ALTER TABLE parts ADD COLUMN retired_at_ms INTEGER;
ALTER TABLE process_models ADD COLUMN retired_at_ms INTEGER;
-- smc.config.ValidityRange; NULL = valid everywhere.
ALTER TABLE process_models ADD COLUMN validity BLOB;

-- Every change to the catalog: what, when, by whom and why (append-only).
CREATE TABLE catalog_history (
  seq       INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms   INTEGER NOT NULL,
  author    TEXT NOT NULL,
  kind      TEXT NOT NULL CHECK (kind IN ('machine', 'tool', 'material', 'part', 'model')),
  entity_id TEXT NOT NULL,
  action    TEXT NOT NULL,
  reason    TEXT NOT NULL,
  detail    TEXT NOT NULL DEFAULT ''
);
CREATE INDEX catalog_history_by_entity ON catalog_history (kind, entity_id, seq);
CREATE TRIGGER catalog_history_append_only_update BEFORE UPDATE ON catalog_history
BEGIN SELECT RAISE(ABORT, 'catalog_history is append-only'); END;
CREATE TRIGGER catalog_history_append_only_delete BEFORE DELETE ON catalog_history
BEGIN SELECT RAISE(ABORT, 'catalog_history is append-only'); END;
)sql"},
    Migration{4, "stability evidence from cuts", R"sql(
-- What cuts showed about stability, per part, machine and tool (append-only):
-- a chatter event at its speed, depth, width and feed; a chatter-free pass
-- with the revolutions it was cut for.
CREATE TABLE stability_evidence (
  seq               INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms           INTEGER NOT NULL,
  part_id           TEXT NOT NULL,
  machine_id        TEXT NOT NULL,
  tool_id           TEXT NOT NULL,
  job_id            TEXT NOT NULL,
  spindle_rpm       REAL NOT NULL,
  depth_mm          REAL NOT NULL,
  width_mm          REAL NOT NULL,
  feed_per_tooth_mm REAL NOT NULL,
  chatter           INTEGER NOT NULL CHECK (chatter IN (0, 1)),
  frequency_hz      REAL NOT NULL DEFAULT 0,
  revolutions       INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX stability_evidence_by_part ON stability_evidence (part_id, machine_id, tool_id);
CREATE TRIGGER stability_evidence_append_only_update BEFORE UPDATE ON stability_evidence
BEGIN SELECT RAISE(ABORT, 'stability_evidence is append-only'); END;
)sql"},
    Migration{5, "parts that allow a spindle speed change", R"sql(
-- SMC II+ (module O) may move the spindle off the programmed speed only on
-- a part whose tolerances allow it.
ALTER TABLE parts ADD COLUMN speed_change_allowed INTEGER NOT NULL DEFAULT 0
  CHECK (speed_change_allowed IN (0, 1));
)sql"},
    Migration{6, "job history: revolutions and programs as run", R"sql(
-- Per job, what the edge reported of each revolution (force summaries) and
-- each program it ran (the plan's, rewrites, speed changes): the job's
-- history page and export read them after the job and any restart.
CREATE TABLE job_revolutions (
  job_id            TEXT NOT NULL REFERENCES jobs (id),
  attempt           INTEGER NOT NULL,
  t_s               REAL NOT NULL,
  revolution        INTEGER NOT NULL,
  pass_index        INTEGER NOT NULL,
  pass_count        INTEGER NOT NULL,
  depth_mm          REAL NOT NULL,
  f_y_n             REAL NOT NULL,
  f_ref_n           REAL NOT NULL,
  feedrate_mm_s     REAL NOT NULL,
  feed_per_tooth_mm REAL NOT NULL,
  spindle_rpm       REAL NOT NULL,
  spindle_power_w   REAL,
  in_contact        INTEGER NOT NULL,
  chatter           INTEGER NOT NULL
);
CREATE INDEX job_revolutions_by_job ON job_revolutions (job_id, attempt, t_s);
CREATE TABLE job_programs (
  job_id   TEXT NOT NULL REFERENCES jobs (id),
  attempt  INTEGER NOT NULL,
  revision INTEGER NOT NULL,
  time_ms  INTEGER NOT NULL,
  passes   INTEGER NOT NULL,
  gcode    TEXT NOT NULL,
  PRIMARY KEY (job_id, attempt, revision)
);
)sql"},
    Migration{7, "a machine's wideband force channel", R"sql(
-- The wideband F_y channel module E reads (smc.config.WidebandChannel):
-- samples per 0.5 ms edge period (0: the cell's default channel), its
-- anti-alias filter and its noise.
ALTER TABLE machines ADD COLUMN wideband_samples_per_tick INTEGER NOT NULL DEFAULT 0
  CHECK (wideband_samples_per_tick BETWEEN 0 AND 8);
ALTER TABLE machines ADD COLUMN wideband_cutoff_hz REAL NOT NULL DEFAULT 0
  CHECK (wideband_cutoff_hz >= 0);
ALTER TABLE machines ADD COLUMN wideband_filter_order INTEGER NOT NULL DEFAULT 0
  CHECK (wideband_filter_order BETWEEN 0 AND 8);
ALTER TABLE machines ADD COLUMN wideband_noise_rms_n REAL NOT NULL DEFAULT 0
  CHECK (wideband_noise_rms_n >= 0);
)sql"},
};

}  // namespace

std::span<const Migration> migrations() noexcept { return kMigrations; }

void migrate(sqlite3* db, const std::string& file) {
  const int latest = kMigrations.back().version;
  for (const Migration& m : kMigrations) {
    Tx tx(db, file);
    exec(db, file,
         "CREATE TABLE IF NOT EXISTS schema_migrations ("
         " version INTEGER PRIMARY KEY NOT NULL,"
         " description TEXT NOT NULL,"
         " applied_at_ms INTEGER NOT NULL)");
    // Read inside the write transaction: another process may have migrated
    // between our check and now.
    Stmt cur(db, file, "SELECT COALESCE(MAX(version), 0) FROM schema_migrations");
    cur.step();
    const std::int64_t current = cur.int64(0);
    if (current > latest) throw_newer(file, current, latest);
    if (m.version <= current) continue;  // rolled back: nothing written
    exec(db, file, m.sql);
    Stmt(db, file,
         "INSERT INTO schema_migrations (version, description, applied_at_ms) VALUES (?, ?, ?)")
        .bind(m.version, std::string(m.description), now_ms())
        .run();
    tx.commit();
  }
}

void throw_newer(const std::string& file, std::int64_t found, int latest) {
  throw StoreError(file + ": schema version " + std::to_string(found) +
                   " is newer than this smc-cell knows (" + std::to_string(latest) +
                   "); fix: use the smc-cell that wrote it, or a newer one (the database is "
                   "left untouched)");
}

}  // namespace smc::cell::store::detail
