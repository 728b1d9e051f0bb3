// Job intake (validation against the catalog, defaults, ids) and the job
// state machine (compare-and-set transitions, each with its event).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "ids.hpp"
#include "smc/cell/store/store.hpp"
#include "sqlite.hpp"

namespace smc::cell::store {

using detail::Blob;
using detail::or_null;
using detail::Stmt;
using smc::config::JobState;

namespace {

std::string num(double v) {
  std::array<char, 32> buf{};
  std::snprintf(buf.data(), buf.size(), "%g", v);
  return buf.data();
}

std::string list(const std::vector<std::string>& items) {
  std::string s;
  for (std::size_t i = 0; i < items.size(); ++i) s += (i > 0 ? ", " : "") + items[i];
  return s.empty() ? "none" : s;
}

bool valid_job_id(const std::string& id) {
  if (id.empty() || id.size() > kMaxJobIdLength) return false;
  const auto ok = [](char c, bool first) {
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    return alnum || (!first && (c == '-' || c == '_' || c == '.'));
  };
  for (std::size_t i = 0; i < id.size(); ++i) {
    if (!ok(id[i], i == 0)) return false;
  }
  return true;
}

// A number a job may leave at 0 for the part's default. Returns the value
// to use, recording a FieldError when it is unusable.
double check_quantity(std::vector<FieldError>& errors, const char* field, double value,
                      double part_default, const char* unit, const std::string& default_text,
                      double limit, const std::string& limit_text) {
  const std::string f = std::string("job.") + field;
  const std::string leave_out = "leave it out (or 0) for " + default_text;
  if (!std::isfinite(value)) {
    errors.push_back(
        {f, "is not a number", "give a value in " + std::string(unit) + ", or " + leave_out});
    return value;
  }
  if (value < 0) {
    errors.push_back({f, num(value) + " " + unit + " is negative",
                      "give a positive value in " + std::string(unit) + ", or " + leave_out});
    return value;
  }
  const double v = value == 0 ? part_default : value;
  if (limit > 0 && v > limit) {
    errors.push_back(
        {f, num(v) + " " + unit + " exceeds " + limit_text + " (" + num(limit) + " " + unit + ")",
         "give at most " + num(limit) + " " + unit + ", or " + leave_out});
  }
  return v;
}

}  // namespace

// ---------------------------------------------------------------- intake --

namespace {

// Validates `in` against the catalog and returns it with the part's defaults
// filled in. Every problem goes to `errors`.
smc::config::Job resolve(Store& store, sqlite3* db, const std::string& file,
                         const smc::config::Job& in, std::vector<FieldError>& errors) {
  smc::config::Job job = in;
  // The ids in use (not retired) of a catalog table, and the error for a
  // retired entity a job names.
  const auto in_use = [&](const std::string& table) {
    return detail::ids(
        db, file, ("SELECT id FROM " + table + " WHERE retired_at_ms IS NULL ORDER BY id").c_str());
  };
  const auto retired = [&](const char* field, const char* kind, const std::string& id,
                           const std::string& table, const std::string& more = {}) {
    errors.push_back({field, std::string(kind) + " '" + id + "' is retired",
                      "use one of: " + list(in_use(table)) + more});
  };

  if (!job.job_id().empty()) {
    if (!valid_job_id(job.job_id())) {
      errors.push_back({"job.job_id",
                        common::quote(job.job_id()) + " is not a valid job id" +
                            (job.job_id().size() > kMaxJobIdLength
                                 ? " (" + std::to_string(job.job_id().size()) + " characters)"
                                 : ""),
                        "use 1 to " + std::to_string(kMaxJobIdLength) +
                            " letters, digits, '-', '_' or '.', starting with a letter or "
                            "digit, or leave job_id out for the cell to assign one"});
    } else if (store.job(job.job_id())) {
      errors.push_back({"job.job_id", "a job '" + job.job_id() + "' exists already",
                        "choose another job_id, or leave it out for the cell to assign one"});
    }
  }

  std::optional<Part> part;
  if (job.part_id().empty()) {
    errors.push_back({"job.part_id", "missing", "set part_id to one of: " + list(in_use("parts"))});
  } else {
    part = store.part(job.part_id());
    if (!part) {
      errors.push_back({"job.part_id", detail::unknown_ref("part", job.part_id(), in_use("parts")),
                        "use one of the known part ids, or add the part to the cell database"});
    } else if (part->retired_at_ms != 0) {
      retired("job.part_id", "part", part->id, "parts");
      part.reset();
    }
  }

  if (!job.material().empty()) {
    // By id, or by name ("6061-T6 aluminium").
    std::optional<Material> mat = store.material(job.material());
    if (!mat) {
      for (auto& m : store.materials()) {
        if (m.name == job.material()) mat = m;
      }
    }
    if (mat && mat->retired_at_ms != 0) {
      retired("job.material", "material", mat->id, "materials");
    } else if (!mat) {
      errors.push_back({"job.material",
                        detail::unknown_ref("material", job.material(), in_use("materials")),
                        part ? "leave material out for the part's, '" + part->material_id + "'"
                             : "use one of the known material ids"});
    } else if (part && mat->id != part->material_id) {
      errors.push_back({"job.material",
                        "part '" + part->id + "' is made of '" + part->material_id + "', not '" +
                            job.material() + "'",
                        "leave material out, or set it to '" + part->material_id + "'"});
    } else {
      job.set_material(mat->id);
    }
  } else if (part) {
    job.set_material(part->material_id);
  }

  if (job.tool_id().empty() && part) job.set_tool_id(part->tool_id);
  if (job.tool_id().empty()) {
    if (part) {
      errors.push_back({"job.tool_id", "missing, and part '" + part->id + "' names no default tool",
                        "set tool_id to one of: " + list(in_use("tools"))});
    }
  } else if (const auto t = store.tool(job.tool_id()); t && t->retired_at_ms != 0) {
    retired("job.tool_id", "tool", t->id, "tools");
  } else if (!t) {
    errors.push_back({"job.tool_id", detail::unknown_ref("tool", job.tool_id(), in_use("tools")),
                      "use one of the known tool ids, or leave tool_id out for the part's tool"});
  }

  // Machine limits: the named machine's, or the most capable machine's when
  // any may run the job.
  double max_feed = 0, max_rpm = 0;
  std::string limit_of = "every machine's maximum";
  const auto m = job.machine_id().empty() ? std::nullopt : store.machine(job.machine_id());
  if (!job.machine_id().empty()) {
    if (m && m->retired_at_ms != 0) {
      retired("job.machine_id", "machine", m->id, "machines",
              ", or leave machine_id out for any capable machine");
    } else if (!m) {
      errors.push_back({"job.machine_id",
                        detail::unknown_ref("machine", job.machine_id(), in_use("machines")),
                        "use one of the known machine ids, or leave machine_id out for any "
                        "capable machine"});
    }
  }
  if (m) {
    max_feed = m->max_feedrate_mm_s;
    max_rpm = m->max_spindle_rpm;
    limit_of = m->id + "'s maximum";
  } else {
    for (const auto& each : store.machines()) {
      if (each.retired_at_ms != 0) continue;
      max_feed = std::max(max_feed, each.max_feedrate_mm_s);
      max_rpm = std::max(max_rpm, each.max_spindle_rpm);
    }
  }

  const auto dflt = [&](double v, const char* unit) {
    return part ? "the part's " + num(v) + " " + unit : std::string("the part's default");
  };
  job.set_depth_mm(check_quantity(errors, "depth_mm", job.depth_mm(),
                                  part ? part->total_depth_mm : 0, "mm",
                                  dflt(part ? part->total_depth_mm : 0, "mm"), 0, ""));
  job.set_feedrate_mm_s(
      check_quantity(errors, "feedrate_mm_s", job.feedrate_mm_s(), part ? part->feedrate_mm_s : 0,
                     "mm/s", dflt(part ? part->feedrate_mm_s : 0, "mm/s"), max_feed, limit_of));
  job.set_spindle_rpm(check_quantity(errors, "spindle_rpm", job.spindle_rpm(),
                                     part ? part->spindle_rpm : 0, "rpm",
                                     dflt(part ? part->spindle_rpm : 0, "rpm"), max_rpm, limit_of));
  return job;
}

}  // namespace

std::vector<FieldError> Store::validate_job(const smc::config::Job& job) {
  std::vector<FieldError> errors;
  resolve(*this, db_.get(), path_, job, errors);
  return errors;
}

Job Store::submit_job(const smc::config::Job& in, const std::string& reason) {
  // Checked and written under the write lock: nothing can change the
  // catalog or take the job id in between.
  detail::Tx tx(db_.get(), path_);
  std::vector<FieldError> errors;
  smc::config::Job spec = resolve(*this, db_.get(), path_, in, errors);
  if (!errors.empty()) throw JobRejected(std::move(errors));
  if (spec.job_id().empty()) {
    spec.set_job_id(detail::next_id(db_.get(), path_, "job", "SELECT 1 FROM jobs WHERE id = ?"));
  }
  const std::int64_t now = detail::now_ms();
  Stmt(db_.get(), path_,
       "INSERT INTO jobs (id, spec, part_id, state, created_at_ms, updated_at_ms) "
       "VALUES (?, ?, ?, ?, ?, ?)")
      .bind(spec.job_id(), Blob{detail::serialize(spec, "job")}, spec.part_id(),
            static_cast<int>(smc::config::JOB_QUEUED), now, now)
      .run();
  Stmt(db_.get(), path_,
       "INSERT INTO job_events (job_id, seq, time_ms, from_state, to_state, reason, machine_id) "
       "VALUES (?, 1, ?, ?, ?, ?, NULL)")
      .bind(spec.job_id(), now, static_cast<int>(smc::config::JOB_STATE_UNSPECIFIED),
            static_cast<int>(smc::config::JOB_QUEUED), reason)
      .run();
  tx.commit();
  auto stored = job(spec.job_id());
  if (!stored) throw StoreError(path_ + ": submit_job: job '" + spec.job_id() + "' vanished");
  return *stored;
}

// ------------------------------------------------------------ transitions --

std::optional<JobEvent> Store::transition(const std::string& job_id, JobState from, JobState to,
                                          const std::string& reason,
                                          const std::string& machine_id) {
  const std::string where = path_ + ": job '" + job_id + "': " + std::string(state_name(from)) +
                            " -> " + std::string(state_name(to)) + ": ";
  if (!allowed_transition(from, to)) throw StoreError(where + "not an allowed transition");
  if (to == smc::config::JOB_ASSIGNED && machine_id.empty()) {
    throw StoreError(where + "assigning needs the machine_id");
  }
  if (to != smc::config::JOB_ASSIGNED && !machine_id.empty()) {
    throw StoreError(where + "machine_id is only given when assigning");
  }
  detail::Tx tx(db_.get(), path_);
  const auto current = job(job_id);
  if (!current) throw StoreError(where + "unknown job");
  if (to == smc::config::JOB_ASSIGNED) {
    if (!machine(machine_id)) {
      throw StoreError(where +
                       detail::unknown_ref(
                           "machine", machine_id,
                           detail::ids(db_.get(), path_, "SELECT id FROM machines ORDER BY id")));
    }
    if (!current->spec.machine_id().empty() && current->spec.machine_id() != machine_id) {
      throw StoreError(where + "the job asks for machine '" + current->spec.machine_id() +
                       "', not '" + machine_id + "'");
    }
  }
  // The compare-and-set: only from the state the caller saw.
  const std::int64_t now = detail::now_ms();
  const bool assign = to == smc::config::JOB_ASSIGNED;
  const bool requeue = to == smc::config::JOB_QUEUED;
  Stmt(db_.get(), path_,
       "UPDATE jobs SET state = ?1, updated_at_ms = ?2, "
       "machine_id = CASE WHEN ?3 THEN ?4 WHEN ?5 THEN NULL ELSE machine_id END, "
       "attempt = attempt + ?3 WHERE id = ?6 AND state = ?7")
      .bind(static_cast<int>(to), now, assign, machine_id, requeue, job_id, static_cast<int>(from))
      .run();
  if (sqlite3_changes(db_.get()) == 0) return std::nullopt;  // not in `from` any more

  JobEvent e{job_id, 0, now, from, to, reason, assign ? machine_id : std::string()};
  if (!assign && !requeue) e.machine_id = current->machine_id;
  Stmt next(db_.get(), path_, "SELECT COALESCE(MAX(seq), 0) + 1 FROM job_events WHERE job_id = ?");
  next.bind(job_id).step();
  e.seq = next.int64(0);
  Stmt(db_.get(), path_,
       "INSERT INTO job_events (job_id, seq, time_ms, from_state, to_state, reason, machine_id) "
       "VALUES (?, ?, ?, ?, ?, ?, ?)")
      .bind(job_id, e.seq, now, static_cast<int>(from), static_cast<int>(to), reason,
            or_null(e.machine_id))
      .run();
  tx.commit();
  return e;
}

void Store::set_plan(const std::string& job_id, smc::config::SmcVariant variant,
                     const std::string& explanation, const smc::config::SupervisorConfig& plan,
                     const std::string& planned_for, const std::vector<std::string>& model_ids) {
  const std::string where = path_ + ": set_plan: job '" + job_id + "': ";
  detail::Tx tx(db_.get(), path_);
  if (!planned_for.empty() && !machine(planned_for)) {
    throw StoreError(
        where +
        detail::unknown_ref("machine", planned_for,
                            detail::ids(db_.get(), path_, "SELECT id FROM machines ORDER BY id")));
  }
  Stmt(db_.get(), path_,
       "UPDATE jobs SET variant = ?, explanation = ?, plan = ?, planned_for = ?, "
       "updated_at_ms = ? WHERE id = ? AND state IN (?, ?)")
      .bind(static_cast<int>(variant), explanation,
            Blob{detail::serialize(plan, "supervisor configuration")}, or_null(planned_for),
            detail::now_ms(), job_id, static_cast<int>(smc::config::JOB_QUEUED),
            static_cast<int>(smc::config::JOB_PLANNED))
      .run();
  if (sqlite3_changes(db_.get()) == 0) {
    const auto j = job(job_id);
    throw StoreError(where + (j ? "is " + std::string(state_name(j->state)) +
                                      "; a plan is set only while queued or planned"
                                : std::string("is unknown")));
  }
  Stmt(db_.get(), path_, "DELETE FROM job_plan_models WHERE job_id = ?").bind(job_id).run();
  for (const auto& id : model_ids) {
    if (!model(id)) throw StoreError(where + "unknown model '" + id + "'");
    Stmt(db_.get(), path_, "INSERT OR IGNORE INTO job_plan_models (job_id, model_id) VALUES (?, ?)")
        .bind(job_id, id)
        .run();
  }
  tx.commit();
}

std::vector<std::string> Store::plan_models(const std::string& job_id) {
  Stmt s(db_.get(), path_,
         "SELECT model_id FROM job_plan_models WHERE job_id = ? ORDER BY model_id");
  s.bind(job_id);
  std::vector<std::string> out;
  while (s.step()) out.push_back(s.text(0));
  return out;
}

JobEvent Store::note_event(const std::string& job_id, const std::string& reason) {
  detail::Tx tx(db_.get(), path_);
  const auto current = job(job_id);
  if (!current) throw StoreError(path_ + ": note_event: unknown job '" + job_id + "'");
  const std::int64_t now = detail::now_ms();
  JobEvent e{job_id, 0, now, current->state, current->state, reason, current->machine_id};
  Stmt next(db_.get(), path_, "SELECT COALESCE(MAX(seq), 0) + 1 FROM job_events WHERE job_id = ?");
  next.bind(job_id).step();
  e.seq = next.int64(0);
  Stmt(db_.get(), path_,
       "INSERT INTO job_events (job_id, seq, time_ms, from_state, to_state, reason, machine_id) "
       "VALUES (?, ?, ?, ?, ?, ?, ?)")
      .bind(job_id, e.seq, now, static_cast<int>(e.from_state), static_cast<int>(e.to_state),
            reason, or_null(e.machine_id))
      .run();
  tx.commit();
  return e;
}

void Store::record_result(const std::string& job_id, const smc::config::RunSummary& result) {
  detail::Tx tx(db_.get(), path_);
  Stmt(db_.get(), path_,
       "UPDATE jobs SET result = ?, updated_at_ms = ? WHERE id = ? AND state IN (?, ?, ?, ?)")
      .bind(Blob{detail::serialize(result, "run summary")}, detail::now_ms(), job_id,
            static_cast<int>(smc::config::JOB_RUNNING), static_cast<int>(smc::config::JOB_DONE),
            static_cast<int>(smc::config::JOB_FAILED),
            static_cast<int>(smc::config::JOB_INTERRUPTED))
      .run();
  if (sqlite3_changes(db_.get()) == 0) {
    const auto j = job(job_id);
    throw StoreError(
        path_ + ": record_result: job '" + job_id + "' " +
        (j ? "is " + std::string(state_name(j->state)) + "; results are recorded once it runs"
           : std::string("is unknown")));
  }
  tx.commit();
}

// ------------------------------------------------------------------ reads --

namespace {

const char* const kJobCols =
    "SELECT seq, id, spec, state, COALESCE(machine_id, ''), variant, explanation, attempt, "
    "created_at_ms, updated_at_ms, CASE WHEN ?1 THEN plan END, CASE WHEN ?1 THEN result END, "
    "COALESCE(planned_for, '') "
    "FROM jobs ";

Job read_job(const Stmt& s, const std::string& file) {
  Job j;
  j.seq = s.int64(0);
  j.id = s.text(1);
  detail::deserialize(s.blob(2), j.spec, file, "jobs '" + j.id + "' spec");
  j.state = static_cast<JobState>(s.int64(3));
  j.machine_id = s.text(4);
  j.variant = static_cast<smc::config::SmcVariant>(s.int64(5));
  j.explanation = s.text(6);
  j.attempt = static_cast<std::uint32_t>(s.int64(7));
  j.created_at_ms = s.int64(8);
  j.updated_at_ms = s.int64(9);
  if (!s.is_null(10)) {
    detail::deserialize(s.blob(10), j.plan.emplace(), file, "jobs '" + j.id + "' plan");
  }
  if (!s.is_null(11)) {
    detail::deserialize(s.blob(11), j.result.emplace(), file, "jobs '" + j.id + "' result");
  }
  j.planned_for = s.text(12);
  return j;
}

}  // namespace

std::vector<Job> Store::jobs(const JobFilter& filter) {
  Stmt s(db_.get(), path_,
         std::string(kJobCols) + "WHERE (?2 = 0 OR state = ?2) AND seq > ?3 ORDER BY seq");
  s.bind(filter.with_documents, filter.state ? static_cast<int>(*filter.state) : 0,
         filter.after_seq);
  std::vector<Job> out;
  while (s.step()) out.push_back(read_job(s, path_));
  return out;
}

std::optional<Job> Store::job(const std::string& id) {
  Stmt s(db_.get(), path_, std::string(kJobCols) + "WHERE id = ?2");
  s.bind(true, id);
  if (!s.step()) return std::nullopt;
  return read_job(s, path_);
}

std::vector<JobEvent> Store::events(const std::string& job_id) {
  Stmt s(db_.get(), path_,
         "SELECT job_id, seq, time_ms, from_state, to_state, reason, COALESCE(machine_id, '') "
         "FROM job_events WHERE job_id = ? ORDER BY seq");
  s.bind(job_id);
  std::vector<JobEvent> out;
  while (s.step()) {
    out.push_back(JobEvent{s.text(0), s.int64(1), s.int64(2), static_cast<JobState>(s.int64(3)),
                           static_cast<JobState>(s.int64(4)), s.text(5), s.text(6)});
  }
  return out;
}

void Store::append_revolutions(const std::string& job_id, const std::vector<JobRevolution>& revs) {
  if (revs.empty()) return;
  detail::Tx tx(db_.get(), path_);
  Stmt s(
      db_.get(), path_,
      "INSERT INTO job_revolutions (job_id, attempt, t_s, revolution, pass_index, pass_count, "
      "depth_mm, f_y_n, f_ref_n, feedrate_mm_s, feed_per_tooth_mm, spindle_rpm, "
      "spindle_power_w, in_contact, chatter) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const auto& r : revs) {
    s.bind(job_id, static_cast<std::int64_t>(r.attempt), r.t_s,
           static_cast<std::int64_t>(r.revolution), static_cast<std::int64_t>(r.pass_index),
           static_cast<std::int64_t>(r.pass_count), r.depth_mm, r.f_y_n, r.f_ref_n, r.feedrate_mm_s,
           r.feed_per_tooth_mm, r.spindle_rpm,
           std::isnan(r.spindle_power_w) ? std::optional<double>() : r.spindle_power_w,
           static_cast<std::int64_t>(r.in_contact ? 1 : 0),
           static_cast<std::int64_t>(r.chatter ? 1 : 0));
    s.run();
    s.reset();
  }
  tx.commit();
}

std::vector<JobRevolution> Store::revolutions(const std::string& job_id) {
  Stmt s(db_.get(), path_,
         "SELECT attempt, t_s, revolution, pass_index, pass_count, depth_mm, f_y_n, f_ref_n, "
         "feedrate_mm_s, feed_per_tooth_mm, spindle_rpm, spindle_power_w, in_contact, chatter "
         "FROM job_revolutions WHERE job_id = ? ORDER BY attempt, t_s");
  s.bind(job_id);
  std::vector<JobRevolution> out;
  while (s.step()) {
    JobRevolution r;
    r.attempt = static_cast<std::uint32_t>(s.int64(0));
    r.t_s = s.real(1);
    r.revolution = static_cast<std::uint32_t>(s.int64(2));
    r.pass_index = static_cast<std::uint32_t>(s.int64(3));
    r.pass_count = static_cast<std::uint32_t>(s.int64(4));
    r.depth_mm = s.real(5);
    r.f_y_n = s.real(6);
    r.f_ref_n = s.real(7);
    r.feedrate_mm_s = s.real(8);
    r.feed_per_tooth_mm = s.real(9);
    r.spindle_rpm = s.real(10);
    r.spindle_power_w = s.is_null(11) ? std::nan("") : s.real(11);
    r.in_contact = s.int64(12) != 0;
    r.chatter = s.int64(13) != 0;
    out.push_back(r);
  }
  return out;
}

void Store::add_program(const std::string& job_id, const JobProgram& p) {
  Stmt(db_.get(), path_,
       "INSERT OR IGNORE INTO job_programs (job_id, attempt, revision, time_ms, passes, gcode) "
       "VALUES (?, ?, ?, ?, ?, ?)")
      .bind(job_id, static_cast<std::int64_t>(p.attempt), static_cast<std::int64_t>(p.revision),
            p.time_ms != 0 ? p.time_ms : detail::now_ms(), static_cast<std::int64_t>(p.passes),
            p.gcode)
      .run();
}

std::vector<JobProgram> Store::programs(const std::string& job_id) {
  Stmt s(db_.get(), path_,
         "SELECT attempt, revision, time_ms, passes, gcode FROM job_programs WHERE job_id = ? "
         "ORDER BY attempt, revision");
  s.bind(job_id);
  std::vector<JobProgram> out;
  while (s.step()) {
    out.push_back({static_cast<std::uint32_t>(s.int64(0)), static_cast<std::uint32_t>(s.int64(1)),
                   s.int64(2), s.text(4), static_cast<std::uint32_t>(s.int64(3))});
  }
  return out;
}

}  // namespace smc::cell::store
