#pragma once
// The cell database: one SQLite file in WAL mode, shared by the running cell
// service and the smc-cell CLI (each with its own Store). Schema and state
// machine: cell/store/README.md.
//
// A Store is one connection: use it from one thread at a time. Every write
// is one transaction, durable when the call returns (synchronous=FULL);
// concurrent writers from other processes wait (busy timeout), they never
// interleave. Nothing here is for a real-time loop.
//
// Errors: StoreError names the file and the SQL or call that failed;
// JobRejected lists every problem with a submitted job, field by field.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "smc/cell/store/entities.hpp"
#include "smc/common/diagnostic.hpp"

struct sqlite3;

namespace smc::cell::store {

struct StoreError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One problem with a job, as the project's diagnostic: where = the field
// ("job.part_id"), message ("unknown part 'x' (known: a, b)"), fix ("use one
// of the known part ids, or add the part to the database"); str() is
// "job.part_id: unknown part 'x' (...); fix: ...".
using FieldError = common::Diagnostic;

// A job refused by submit_job; nothing was written. what() is every
// FieldError, one per line.
struct JobRejected : StoreError {
  explicit JobRejected(std::vector<FieldError> errors);
  std::vector<FieldError> errors;
};

// The longest job id: the job id travels in 63-character wire strings, and so
// does its configuration's id "<job>-a<attempt>", which needs 12 more (the
// cell service checks this against the IDL at compile time).
inline constexpr std::size_t kMaxJobIdLength = 48;

// The database the cell and its CLI use unless told otherwise:
// $SMC_CELL_DB when set and non-empty, else "smc-cell.db" (current folder).
std::string default_db_path();

enum class OpenMode : std::uint8_t {
  kCreate,    // create the file if it is missing
  kExisting,  // a missing file is an error ("run smc-cell db init")
};

struct JobFilter {
  std::optional<smc::config::JobState> state;  // only jobs in this state
  std::int64_t after_seq = 0;                  // only jobs submitted after this seq
  bool with_documents = false;                 // also load plan and result
};

struct Counts {
  std::int64_t machines = 0, tools = 0, materials = 0, parts = 0, models = 0;
  std::int64_t jobs = 0, job_events = 0;
  std::vector<std::pair<smc::config::JobState, std::int64_t>> jobs_by_state;  // non-zero only
};

class Store {
 public:
  // Opens (kCreate: creates) the database and brings its schema up to
  // latest_schema_version(), each migration in its own transaction. Sets WAL
  // mode, foreign keys, synchronous=FULL and a busy timeout. Refuses a file
  // that is not an smc-cell database, or one migrated by a newer smc-cell.
  static Store open(const std::string& path, OpenMode mode = OpenMode::kCreate);
  static int latest_schema_version() noexcept;

  Store(Store&&) noexcept;
  Store& operator=(Store&&) noexcept;
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;
  ~Store();

  const std::string& path() const noexcept { return path_; }
  int schema_version();
  Counts counts();

  // Runs `body` in one write transaction (nested calls join it as a
  // savepoint). An exception rolls back everything `body` wrote.
  void transaction(const std::function<void()>& body);

  // Changes whenever ANOTHER connection (another process, or another Store
  // on the same file) commits; this Store's own commits leave it alone. A
  // cheap poll for a running service: when it changed, look for new jobs
  // with jobs({.state = JOB_QUEUED, .after_seq = last_seen_seq}).
  std::int64_t data_version();

  // ------------------------------------------------------------- catalog --
  // put_*: insert, or update the row with the same id.
  void put_machine(const Machine& m);
  void put_tool(const Tool& t);
  void put_material(const Material& m);
  void put_part(const Part& p);
  std::vector<Machine> machines();
  std::vector<Tool> tools();
  std::vector<Material> materials();
  std::vector<Part> parts();
  std::optional<Machine> machine(const std::string& id);
  std::optional<Tool> tool(const std::string& id);
  std::optional<Material> material(const std::string& id);
  std::optional<Part> part(const std::string& id);

  // -------------------------------------------------------------- models --
  // Stores a model (a learnt candidate: provenance FITTED, validated false,
  // its FitStatistics). Assigns an id when m.id is empty; returns the id.
  // References must exist; an existing id is an error.
  std::string add_model(const ProcessModel& m);
  std::optional<ProcessModel> model(const std::string& id);
  // Marks a model validated (or not) after a validation run; validating a
  // model clears a suspicion.
  void set_model_validated(const std::string& id, bool validated);
  // Marks a model suspect, with the reason (evidence against it: a cut
  // planned from it chattered). A suspect model is not used for SMC I.
  void mark_model_suspect(const std::string& id, const std::string& reason);
  // Every model for the combination, so the cell can explain its choice.
  // Retired models are left out. An empty machine_id, tool_id or material_id matches any; a part_id
  // matches models for that part and models for any part (part_id empty in
  // the row); an empty part_id matches every model. Order: part-specific
  // first, then validated, then provenance (identified, fitted, handbook),
  // then newest first.
  std::vector<ProcessModel> find_models(const std::string& machine_id, const std::string& tool_id,
                                        const std::string& material_id, const std::string& part_id);

  // ------------------------------------------------------------- history --
  // Appends one change to the catalog's history (in the caller's
  // transaction when there is one). An empty author is recorded as "unknown".
  void record_catalog_event(const std::string& kind, const std::string& entity_id,
                            const std::string& action, const std::string& author,
                            const std::string& reason, const std::string& detail = {});
  // The history of one entity (or of a kind, or of everything, with empty
  // arguments), oldest first.
  std::vector<CatalogEvent> history(const std::string& kind = {},
                                    const std::string& entity_id = {});

  // What cuts showed about stability (append-only): a chatter event bounds
  // the stable depth from above at its speed, a chatter-free pass from below.
  void add_stability_evidence(const StabilityEvidence& e);
  // A part's evidence, oldest first.
  std::vector<StabilityEvidence> stability_evidence(const std::string& part_id);
  // Retires a machine, tool, material, part or model (kind as in the
  // history): it stays in the database for the jobs that used it, and new
  // jobs and plans refuse it; a retired machine's planned jobs are planned
  // again. Recorded in the history. StoreError for an
  // unknown kind or id, one retired already, or an empty reason.
  void retire(const std::string& kind, const std::string& id, const std::string& author,
              const std::string& reason);

  // ---------------------------------------------------------------- jobs --
  // Checks a job against the catalog without writing; every problem found.
  std::vector<FieldError> validate_job(const smc::config::Job& job);
  // Accepts a job: validates it (JobRejected, nothing written), fills the
  // part's defaults into empty material/tool/depth/feedrate/speed, assigns
  // "job-NNNNNN" when job_id is empty (monotonic, never reused), stores it
  // QUEUED with its first event (UNSPECIFIED → QUEUED, `reason`). Durable
  // when it returns.
  Job submit_job(const smc::config::Job& job, const std::string& reason = "submitted");
  // Compare-and-set of the state: moves the job from `from` to `to` only if
  // it is in `from` now, and records the event (time, reason) in the same
  // transaction. Returns std::nullopt when the job is no longer in `from`
  // (another dispatcher got there first: do nothing). Throws StoreError for
  // an unknown job or a transition allowed_transition() refuses. To
  // JOB_ASSIGNED it requires `machine_id` (a known machine), records it and
  // counts an attempt.
  std::optional<JobEvent> transition(const std::string& job_id, smc::config::JobState from,
                                     smc::config::JobState to, const std::string& reason,
                                     const std::string& machine_id = {});
  // Records the plan of a QUEUED or PLANNED job (StoreError otherwise):
  // `planned_for` is the machine whose models the plan used (empty: any
  // machine), `model_ids` those models (replacing an earlier plan's).
  void set_plan(const std::string& job_id, smc::config::SmcVariant variant,
                const std::string& explanation, const smc::config::SupervisorConfig& plan,
                const std::string& planned_for = {},
                const std::vector<std::string>& model_ids = {});
  // The models the job's current plan was made from, in id order.
  std::vector<std::string> plan_models(const std::string& job_id);
  // Records an event in the job's history without changing its state (from
  // and to are its current state): something the cell learnt about the job,
  // e.g. a chatter event. Returns the event.
  JobEvent note_event(const std::string& job_id, const std::string& reason);
  // Records what a run achieved (job RUNNING or finished).
  void record_result(const std::string& job_id, const smc::config::RunSummary& result);
  std::vector<Job> jobs(const JobFilter& filter = {});  // in submission order
  std::optional<Job> job(const std::string& id);
  std::vector<JobEvent> events(const std::string& job_id);  // in order
  // The job's recorded revolutions (appended in one transaction) and the
  // programs it ran (a revision recorded once per attempt), in order.
  void append_revolutions(const std::string& job_id, const std::vector<JobRevolution>& revs);
  std::vector<JobRevolution> revolutions(const std::string& job_id);
  void add_program(const std::string& job_id, const JobProgram& program);
  std::vector<JobProgram> programs(const std::string& job_id);

 private:
  struct Close {
    void operator()(sqlite3* db) const noexcept;
  };
  Store(std::string path, sqlite3* db) noexcept;

  std::string path_;
  std::unique_ptr<sqlite3, Close> db_;
};

}  // namespace smc::cell::store
