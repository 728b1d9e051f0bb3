#include "smc/supervision/grafcet_binding.hpp"

#include <string>

#include "smc/grafcet/parser.hpp"
#include "smc/grafcet/verifier.hpp"

namespace smc::supervision {

BoundGrafcet bind_grafcet(std::string_view text, std::string_view source_name, ModuleMask allowed,
                          const CheckBudget& budget) {
  if (text.size() > budget.max_text_bytes) {
    throw ConfigError(common::Diagnostic{
        std::string(source_name),
        "the Grafcet text is " + std::to_string(text.size()) + " bytes; at most " +
            std::to_string(budget.max_text_bytes),
        "a supervisor's Grafcet is a few kilobytes; check that this is the right file"});
  }
  grafcet::ParseResult parsed = grafcet::parse(text, source_name);
  if (!parsed.ok()) {
    // Each parse error names its own file:line:col.
    common::Diagnostics problems;
    for (const auto& d : parsed.errors) {
      problems.add("", "operation supervisor: the Grafcet does not parse: " + d.str());
    }
    throw ConfigError(std::move(problems));
  }
  BoundGrafcet b{std::move(*parsed.grafcet), {}, {}};
  const auto& g = b.grafcet;
  const std::string where(source_name);

  // Cheap checks first: the names must be the edge's before any exhaustive work.
  common::Diagnostics problems;
  for (size_t i = 0; i < g.actions().size(); ++i) {
    const std::string& name = g.actions()[i].name;
    const auto id = module_from_letter(name);
    if (!id) {
      problems.add(where, "action " + common::quote(name, 16) + " is not a module",
                   "actions must be module letters A to L");
      continue;
    }
    if (!has(allowed, *id)) {
      problems.add(where,
                   "action '" + name + "' uses module " + name +
                       ", which the configuration's module set does not include",
                   "add " + name + " to the configuration's modules or remove the action");
      continue;
    }
    b.action_module[i] = bit(*id);
  }
  b.input_index.fill(-1);
  for (size_t i = 0; i < g.inputs().size(); ++i) {
    const std::string& name = g.inputs()[i].name;
    if (name.size() != 1 || name[0] < 'a' || name[0] >= 'a' + kReceptivityCount) {
      problems.add(where,
                   "input " + common::quote(name, 16) +
                       " is not a receptivity of the state supervisor (a to h)",
                   "use only the receptivities a to h (services/grafcet/README.md)");
      continue;
    }
    b.input_index[static_cast<size_t>(name[0] - 'a')] = static_cast<int>(i);
  }
  if (!problems.ok()) throw ConfigError(std::move(problems));

  grafcet::VerifyOptions vo;
  vo.max_work = budget.max_work;
  vo.max_time = budget.max_time;
  const grafcet::Report report = grafcet::verify(g, vo);
  if (!report.ok()) {
    // One diagnostic per line of the verifier's report (each is one finding
    // or one step of its shortest input path).
    const std::string found = grafcet::format_report(g, report);
    size_t start = 0;
    while (start < found.size()) {
      size_t end = found.find('\n', start);
      if (end == std::string::npos) end = found.size();
      if (end > start) {
        problems.add(where, "operation supervisor: the Grafcet fails verification: " +
                                found.substr(start, end - start));
      }
      start = end + 1;
    }
    throw ConfigError(std::move(problems));
  }
  return b;
}

}  // namespace smc::supervision
