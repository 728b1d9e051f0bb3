#pragma once
// Seed data for the demo cell: the catalog documents of cell/catalog/ — the
// paper's machine (as "mill-1" and "mill-2"), its face mill and 6061-T6
// aluminium; a transfer-line part with validated models ("bracket-tl",
// SMC I) and job-shop parts without any ("housing-js", SMC II; "cover-jsp",
// which allows a spindle speed change, SMC II+) — applied
// exactly as `smc-cell catalog apply cell/catalog` would.

#include <cstdint>
#include <string>

namespace smc::cell::store {

class Store;

struct SeedOptions {
  std::string catalog_dir;  // empty: default_catalog_dir() (cell/catalog)
};

// Idempotent: applies the folder's documents (catalog_docs.hpp) with author
// "seed"; what exists unchanged stays. Returns the number of entities
// created (0 on a re-seed). Throws CatalogError (file:line:col, or file:
// field: problem; fix) for a bad document; nothing is written then.
std::int64_t seed_demo(Store& store, const SeedOptions& options = {});

}  // namespace smc::cell::store
