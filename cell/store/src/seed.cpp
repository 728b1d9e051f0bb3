// Demo seed data: the documents of cell/catalog/ (the paper's numbers are
// data there and in cell/models/, never in code).

#include "smc/cell/store/seed.hpp"

#include "smc/cell/store/catalog_docs.hpp"

namespace smc::cell::store {

std::int64_t seed_demo(Store& store, const SeedOptions& options) {
  const std::string dir = options.catalog_dir.empty() ? default_catalog_dir() : options.catalog_dir;
  ApplyOptions apply;
  apply.author = "seed";
  apply.reason = "demo seed (" + dir + ")";
  std::int64_t created = 0;
  for (const auto& c : apply_catalog(store, load_catalog({dir}), apply)) {
    created += c.action == "created" ? 1 : 0;
  }
  return created;
}

}  // namespace smc::cell::store
