#pragma once
// The catalog as documents (smc.config.Catalog, textproto or JSON):
// `smc-cell catalog apply` reads them into the database, `catalog export`
// writes the database back as documents. README.md, "Catalog documents".

#include <string>
#include <vector>

#include "smc/cell/store/store.hpp"
#include "smc/common/diagnostic.hpp"
#include "smc_config.pb.h"

namespace smc::cell::store {

// Documents that cannot be read or applied: one problem per line, each
// starting with the file ("path:line:col: ..." for a parse error, "path:
// machines[0] 'mill-3'.max_spindle_power_w: must be > 0, got -5; fix: ...").
struct CatalogError : common::DiagnosticError {
  using common::DiagnosticError::DiagnosticError;
};

template <class T>
struct FromFile {
  std::string file;
  int index = 0;  // within its kind in that file
  T doc;
};

struct CatalogDocuments {
  std::vector<FromFile<smc::config::CatalogMachine>> machines;
  std::vector<FromFile<smc::config::CatalogTool>> tools;
  std::vector<FromFile<smc::config::CatalogMaterial>> materials;
  std::vector<FromFile<smc::config::CatalogPart>> parts;
  std::vector<FromFile<smc::config::CatalogModel>> models;
};

// Reads files and folders (a folder: its .textproto, .txtpb, .pbtxt and
// .json files, in name order). A model's milling_file / force_process_file
// is read relative to its document. Throws CatalogError.
CatalogDocuments load_catalog(const std::vector<std::string>& paths);

// The machine a document describes, as apply_catalog would store it (its
// defaults filled in: name, drive, a channel's filter order).
Machine machine_from_doc(const smc::config::CatalogMachine& doc);

struct CatalogChange {
  std::string kind;  // machine, tool, material, part, model
  std::string id;
  std::string action;  // created, updated, unchanged
  std::string detail;  // the fields that change, for an update
};

struct ApplyOptions {
  bool dry_run = false;  // check and report the changes; write nothing
  std::string author;    // recorded in the history ("unknown" when empty)
  std::string reason = "catalog apply";
};

// Checks every document against the others and the database (ids, limits,
// references, models: a model id is never given another document) and, when
// all is well and not a dry run, writes every change in one transaction with
// its history row. Idempotent: applying the same documents again changes
// nothing. Throws CatalogError listing every problem; nothing is written.
std::vector<CatalogChange> apply_catalog(Store& store, const CatalogDocuments& docs,
                                         const ApplyOptions& options);

// The database's catalog in use (retired entities left out) as one document.
smc::config::Catalog export_catalog(Store& store);

// Writes it as machines.textproto, tools.textproto, materials.textproto,
// parts.textproto and models.textproto in `dir` (created). Returns the files.
std::vector<std::string> write_catalog(const smc::config::Catalog& catalog, const std::string& dir);

// The shipped catalog folder (cell/catalog/ of the source tree).
std::string default_catalog_dir();

}  // namespace smc::cell::store
