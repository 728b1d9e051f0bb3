#include "smc/machining/paper_case.hpp"

#include "smc/machining/model_proto.hpp"

namespace smc::machining {

namespace detail {
extern const std::string_view kPaperCaseText;
extern const std::string_view kPaperForceModelText;
}  // namespace detail

std::string_view paper_case_text() noexcept { return detail::kPaperCaseText; }
std::string_view paper_force_model_text() noexcept { return detail::kPaperForceModelText; }

MillingModel paper_case() {
  return parse_milling_model(std::string(detail::kPaperCaseText), false,
                             "cell/models/paper_face_mill.textproto");
}

ForceProcessModel paper_force_process_model() {
  return parse_force_process_model(std::string(detail::kPaperForceModelText), false,
                                   "cell/models/paper_force_model.textproto");
}

}  // namespace smc::machining
