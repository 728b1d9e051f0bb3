#pragma once
// Rows of the cell database as plain values. Documents (jobs, models, plans)
// are the configuration-plane messages of idl/smc_config.proto; the database
// keeps them serialized and the columns the cell queries by beside them.
// Times are milliseconds since the Unix epoch (UTC).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "smc_config.pb.h"

namespace smc::cell::store {

// A machine's wideband F_y channel, which module E reads
// (smc.config.WidebandChannel). samples_per_tick 0: the cell's defaults.
struct WidebandChannel {
  std::uint32_t samples_per_tick = 0;  // per 0.5 ms edge period: 1 (2 kHz) to 5 (10 kHz)
  double cutoff_hz = 0;
  std::uint32_t filter_order = 0;
  double noise_rms_n = 0;
  bool is_default() const noexcept { return samples_per_tick == 0; }
  // Its rate: samples_per_tick samples each 0.5 ms edge period.
  double rate_hz() const noexcept { return 2000.0 * samples_per_tick; }
  // Its filter's order (0: the default second).
  int order() const noexcept { return filter_order == 0 ? 2 : static_cast<int>(filter_order); }
};

struct Machine {
  std::string id;  // "mill-1"
  std::string name;
  double max_spindle_power_w = 0;
  double max_feedrate_mm_s = 0;
  double max_spindle_rpm = 0;
  double min_spindle_rpm = 0;
  std::string drive = "simulated";  // or "linuxcnc"
  std::int64_t retired_at_ms = 0;   // 0: in use
  WidebandChannel wideband;         // schema v7
};

struct Tool {
  std::string id;  // "fm-r25-4t"
  std::string name;
  std::uint32_t teeth = 0;
  double radius_mm = 0;
  double lead_angle_deg = 0;
  std::int64_t retired_at_ms = 0;  // 0: in use
};

struct Material {
  std::string id;  // "6061-T6"
  std::string name;
  std::int64_t retired_at_ms = 0;  // 0: in use
};

// A part and the defaults of its part program. Geometry follows
// smc.config.Workpiece: width across the feed, centre line offset from the
// cutter axis, length along the feed.
struct Part {
  std::string id;
  std::string name;
  std::string material_id;
  std::string tool_id;  // default tool of its program
  double width_mm = 0;
  double offset_mm = 0;
  double length_mm = 0;
  double total_depth_mm = 0;       // depth its program removes
  double feedrate_mm_s = 0;        // programmed feedrate
  double spindle_rpm = 0;          // programmed spindle speed
  std::int64_t retired_at_ms = 0;  // 0: in use
  // Its tolerances allow the spindle to leave the programmed speed (a
  // chatter remedy of SMC II+, module O).
  bool speed_change_allowed = false;
};

enum class ModelKind : std::uint8_t {
  kForceProcess = 1,  // eq. (1): smc.config.ForceProcessModel
  kMilling = 2,       // structural + cutting law: smc.config.MillingModel
};

// A process model for one machine, tool and material, optionally for one
// part (part_id empty: any part of that material). Exactly one of `force`
// and `milling` is meaningful, chosen by `kind`; their provenance and
// validated fields are kept equal to the row's.
struct ProcessModel {
  std::string id;  // empty on add_model: the store assigns "model-000001", ...
  ModelKind kind = ModelKind::kForceProcess;
  std::string machine_id;
  std::string tool_id;
  std::string material_id;
  std::string part_id;
  smc::config::Provenance provenance = smc::config::PROVENANCE_UNSPECIFIED;
  bool validated = false;
  smc::config::ForceProcessModel force;
  smc::config::MillingModel milling;
  smc::config::FitStatistics fit;  // FITTED models: statistics of the fit
  std::string note;                // where it came from, in words
  std::int64_t created_at_ms = 0;
  // Non-empty: why the model is suspect (a cut planned from it chattered).
  // A suspect model is listed but not used for SMC I (Store::mark_model_suspect;
  // set_model_validated(id, true) clears it).
  std::string suspect_reason;
  smc::config::ValidityRange validity;  // all 0: valid everywhere
  std::int64_t retired_at_ms = 0;       // 0: in use
};

// What one cut showed about stability (Store::add_stability_evidence). A
// chatter event is a point at or above the stability limit at its speed; a
// pass cut without chatter for `revolutions` revolutions one below it.
struct StabilityEvidence {
  std::int64_t seq = 0;  // assigned by the store
  std::int64_t time_ms = 0;
  std::string part_id;
  std::string machine_id;
  std::string tool_id;
  std::string job_id;
  double spindle_rpm = 0;
  double depth_mm = 0;
  double width_mm = 0;
  double feed_per_tooth_mm = 0;
  bool chatter = false;
  double frequency_hz = 0;        // chatter: the detector's frequency (0: signalled by hand)
  std::uint32_t revolutions = 0;  // chatter-free: revolutions cut at this depth
};

// One change to the catalog (Store::history).
struct CatalogEvent {
  std::int64_t seq = 0;
  std::int64_t time_ms = 0;
  std::string author;
  std::string kind;  // machine, tool, material, part, model
  std::string entity_id;
  std::string action;  // created, updated, retired, validated, suspected
  std::string reason;
  std::string detail;  // what changed, in words
};

struct Job {
  std::int64_t seq = 0;   // submission order; never reused
  std::string id;         // spec.job_id()
  smc::config::Job spec;  // as submitted, with the part's defaults filled in
  smc::config::JobState state = smc::config::JOB_STATE_UNSPECIFIED;
  std::string machine_id;  // assigned machine; empty before assignment
  smc::config::SmcVariant variant = smc::config::SMC_UNSPECIFIED;
  std::string explanation;  // why this variant (set_plan)
  // The machine whose models the plan used (SMC I): dispatch sends the job
  // only there. Empty: the plan suits any machine (set_plan).
  std::string planned_for;
  std::uint32_t attempt = 0;  // times assigned
  std::int64_t created_at_ms = 0;
  std::int64_t updated_at_ms = 0;
  // Loaded by job(id), and by jobs() only when JobFilter::with_documents.
  std::optional<smc::config::SupervisorConfig> plan;  // set_plan
  std::optional<smc::config::RunSummary> result;      // record_result
};

// One revolution of a job as the cell received it from the edge's force
// summaries (best-effort telemetry: a lost sample is a gap), for the job's
// history page and export.
struct JobRevolution {
  std::uint32_t attempt = 0;
  double t_s = 0;  // machine time since the job's start
  std::uint32_t revolution = 0;
  std::uint32_t pass_index = 0;
  std::uint32_t pass_count = 0;
  double depth_mm = 0;
  double f_y_n = 0;
  double f_ref_n = 0;
  double feedrate_mm_s = 0;
  double feed_per_tooth_mm = 0;
  double spindle_rpm = 0;
  double spindle_power_w = 0;  // NaN: the drive cannot tell
  bool in_contact = false;
  bool chatter = false;
};

// A part program a job ran: the plan's, then each rewrite or speed change
// the edge published.
struct JobProgram {
  std::uint32_t attempt = 0;
  std::uint32_t revision = 0;
  std::int64_t time_ms = 0;
  std::string gcode;
  std::uint32_t passes = 0;
};

struct JobEvent {
  std::string job_id;
  std::int64_t seq = 0;  // 1, 2, ... per job, in order
  std::int64_t time_ms = 0;
  smc::config::JobState from_state = smc::config::JOB_STATE_UNSPECIFIED;  // UNSPECIFIED: submission
  smc::config::JobState to_state = smc::config::JOB_STATE_UNSPECIFIED;
  std::string reason;
  std::string machine_id;  // the job's machine after the event (may be empty)
  // A note (Store::note_event): something learnt about the job, e.g. a
  // chatter event; the state did not change.
  bool is_note() const noexcept { return from_state == to_state; }
};

// The job state machine (README.md):
//   queued → planned → assigned → running → done | failed | interrupted
//   assigned → interrupted, interrupted → queued (re-queue),
//   interrupted → failed (given up), queued | planned → failed (cannot be planned),
//   planned → queued (re-planned: its machine's limits changed).
bool allowed_transition(smc::config::JobState from, smc::config::JobState to) noexcept;
bool is_terminal(smc::config::JobState s) noexcept;  // done, failed

// "queued", "planned", ... ; parse accepts these, any case, and the enum
// names ("JOB_QUEUED").
std::string_view state_name(smc::config::JobState s) noexcept;
std::optional<smc::config::JobState> parse_state(std::string_view text);
std::string_view kind_name(ModelKind k) noexcept;                      // "force-process", "milling"
std::string_view provenance_name(smc::config::Provenance p) noexcept;  // "identified", ...
std::string_view variant_name(smc::config::SmcVariant v) noexcept;     // "SMC I", ...
// A machine's own wideband channel: "2 kHz, order-2 filter at 500 Hz" (the
// edge's 0.5 ms period); "" for the cell's default.
std::string channel_text(const WidebandChannel& w);

// "2024-05-01T12:00:00.123Z"
std::string format_time(std::int64_t time_ms);

}  // namespace smc::cell::store
