#pragma once
// The paper's case as data. The documents are cell/models/paper_face_mill.textproto
// (smc.config.MillingModel: cutter, documented default geometry, A1/A2
// pressures, A6-A9 modes, reference cut 2 mm at 1500 rpm and 10 mm/s) and
// cell/models/paper_force_model.textproto (eq. 1), embedded into the library
// at build time so that tools and tests have them without a file.

#include <string_view>

#include "smc/machining/force_process.hpp"
#include "smc/machining/model.hpp"

namespace smc::machining {

MillingModel paper_case();
ForceProcessModel paper_force_process_model();

// The embedded documents' text.
std::string_view paper_case_text() noexcept;
std::string_view paper_force_model_text() noexcept;

}  // namespace smc::machining
