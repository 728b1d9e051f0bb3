#pragma once
// Seed data for the demo cell: the paper's machine (as "mill-1" and
// "mill-2"), its face mill and 6061-T6 aluminium; a transfer-line part with
// validated models ("bracket-tl", SMC I) and a job-shop part without any
// ("housing-js", SMC II). Values and their sources: cell/store/README.md.

#include <cstdint>
#include <string>

namespace smc::cell::store {

class Store;

struct SeedOptions {
  // Folder holding paper_face_mill.textproto (smc.config.MillingModel) and
  // paper_force_model.textproto (smc.config.ForceProcessModel). A document
  // missing there is replaced by the built-in paper values; an empty string
  // uses the built-in values only.
  std::string models_dir;
};

// The repository's cell/models folder (compiled in).
std::string default_models_dir();

// Idempotent: inserts what is missing, changes nothing that exists, all in
// one transaction. Returns the number of rows inserted (0 on a re-seed).
// Throws smc::documents::DocumentError (file:line:col) for a malformed
// model document; nothing is written then.
std::int64_t seed_demo(Store& store, const SeedOptions& options = {});

}  // namespace smc::cell::store
