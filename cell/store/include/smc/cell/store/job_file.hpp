#pragma once
// Job files (smc-cell job submit FILE): an smc.config.Job as textproto
// (.textproto, .txtpb, .pbtxt) or JSON (.json).

#include <stdexcept>
#include <string>

#include "smc/cell/store/entities.hpp"
#include "smc/common/diagnostic.hpp"

namespace smc::cell::store {

class Store;

// A job file that could not be read, parsed or accepted. what() is one
// problem per line, each starting with the path: "path:line:col: ..." for a
// parse error, "path: job.part_id: unknown part 'x' (known: ...); fix: ..."
// for a job the catalog refuses.
struct JobFileError : common::DiagnosticError {
  using common::DiagnosticError::DiagnosticError;
};

smc::config::Job load_job_file(const std::string& path);
// Loads and submits; nothing is written when it throws JobFileError.
Job submit_job_file(Store& store, const std::string& path);

}  // namespace smc::cell::store
