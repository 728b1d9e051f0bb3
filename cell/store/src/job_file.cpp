#include "smc/cell/store/job_file.hpp"

#include "smc/cell/store/store.hpp"
#include "smc/documents/load.hpp"

namespace smc::cell::store {

smc::config::Job load_job_file(const std::string& path) {
  smc::config::Job job;
  try {
    smc::documents::load(path, job);
  } catch (const smc::documents::DocumentError& e) {
    throw JobFileError(e.diagnostics());  // already "path:line:col: ..." / "path: ..."
  }
  return job;
}

Job submit_job_file(Store& store, const std::string& path) {
  const smc::config::Job spec = load_job_file(path);
  try {
    return store.submit_job(spec, "submitted from " + path);
  } catch (const JobRejected& e) {
    common::Diagnostics problems;
    for (const auto& fe : e.errors) problems.add(path + ": " + fe.where, fe.message, fe.fix);
    throw JobFileError(std::move(problems));
  }
}

}  // namespace smc::cell::store
