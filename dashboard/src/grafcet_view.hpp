#pragma once
// A mill's operation supervisor as the page draws it: the Grafcet text of its
// SupervisorConfig parsed with smc_grafcet and turned into JSON (steps with
// their designer's numbers and actions, transitions, inputs), plus what is
// needed to map a SupervisorSituation's step-index bitmask to step numbers.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace smc::dashboard {

struct GrafcetView {
  bool ok = false;
  std::string json;                         // always valid JSON; "errors" when !ok
  std::vector<std::uint32_t> step_numbers;  // step index -> designer's number
  std::vector<std::string> input_names;     // input index -> name (a, b, ...)
};

// `source` names the text in error messages (e.g. "smc_config/mill-1").
GrafcetView make_grafcet_view(std::string_view text, std::string_view source);

// Numbers of the steps whose index bit is set; an index the Grafcet does not
// have is reported as 0 (the page shows it as unknown).
std::vector<std::uint32_t> active_step_numbers(const GrafcetView& view, std::uint64_t mask);

}  // namespace smc::dashboard
