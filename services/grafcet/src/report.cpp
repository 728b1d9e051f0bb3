// The verification report as text (smc-cell grafcet check).

#include <bit>
#include <map>

#include "smc/grafcet/verifier.hpp"

namespace smc::grafcet {
namespace {

std::string steps_text(const Grafcet& g, Mask steps) {
  if (steps == 0) return "(no active step)";
  std::string s;
  for (Mask m = steps; m != 0; m &= m - 1) {
    if (!s.empty()) s += ' ';
    s += 'X';
    s += std::to_string(g.steps()[static_cast<std::size_t>(std::countr_zero(m))].number);
  }
  return s;
}

std::string inputs_text(const Grafcet& g, Mask read, Mask values) {
  std::string s;
  for (Mask m = read; m != 0; m &= m - 1) {
    const auto i = static_cast<std::size_t>(std::countr_zero(m));
    if (!s.empty()) s += ' ';
    s += g.inputs()[i].name + "=" + ((values >> i & 1u) != 0 ? "1" : "0");
  }
  return s.empty() ? "(no input read)" : s;
}

std::string impulses_text(const Grafcet& g, Mask impulses) {
  std::string s;
  for (Mask m = impulses; m != 0; m &= m - 1) {
    s += s.empty() ? "fired " : " ";
    s += g.actions()[static_cast<std::size_t>(std::countr_zero(m))].name + "*";
  }
  return s;
}

std::string line_of(SourceLocation w) {
  return w.line == 0 ? std::string() : " (line " + std::to_string(w.line) + ")";
}

void path_text(std::string& out, const Grafcet& g, const Report& r, const Violation& v) {
  if (v.path.empty()) return;
  out += "        shortest input sequence from the initial situation (" +
         std::to_string(v.path.size()) + (v.path.size() == 1 ? " evaluation" : " evaluations") +
         "):\n";
  for (std::size_t k = 0; k < v.path.size(); ++k) {
    const PathStep& p = v.path[k];
    std::string line = std::string("          ").append(std::to_string(k + 1)) + ". " +
                       inputs_text(g, r.inputs_read, p.inputs) + "  ->  " + steps_text(g, p.steps);
    if (!p.stable) line += " ... never stable";
    const std::string imp = impulses_text(g, p.impulses);
    if (!imp.empty()) line += "   " + imp;
    out += line + "\n";
  }
}

}  // namespace

std::string format_report(const Grafcet& g, const Report& r) {
  std::string out = "grafcet " + g.name();
  if (!g.title().empty()) out += " \"" + g.title() + "\"";
  out += " (" + g.source() + ")\n";
  out += "  " + std::to_string(g.steps().size()) + " steps, " +
         std::to_string(g.transitions().size()) + " transitions, " +
         std::to_string(g.inputs().size()) + " inputs (" +
         std::to_string(std::popcount(r.inputs_read)) + " read), " +
         std::to_string(g.actions().size()) + " actions, " + std::to_string(g.orders().size()) +
         (g.orders().size() == 1 ? " checking order, " : " checking orders, ") +
         std::to_string(g.invariants().size()) + " invariants\n";
  out += "  explored " + std::to_string(r.states) + " states x " + std::to_string(r.valuations) +
         " input valuations = " + std::to_string(r.evolutions) + " evolutions; " +
         std::to_string(r.stable_situations) + " stable situations; longest transient " +
         std::to_string(r.longest_transient) + " rounds\n\n";

  std::map<Check, std::vector<const Violation*>> by_check;
  for (const Violation& v : r.violations) by_check[v.check].push_back(&v);

  auto section = [&](Check c, const std::string& ok_text) {
    auto it = by_check.find(c);
    if (it == by_check.end()) {
      if (!ok_text.empty()) out += "  ok    " + ok_text + "\n";
      return;
    }
    for (const Violation* v : it->second) {
      out += "  FAIL  " + std::string(check_name(c)) + ": " + v->subject + line_of(v->where) +
             "\n        " + v->detail + "\n";
      path_text(out, g, r, *v);
    }
  };
  section(Check::kLimit, "");
  section(Check::kUnreachableStep, "reachability: every step is reachable");
  section(Check::kConflict, "conflicts: none left unresolved by the checking orders");
  section(Check::kDeadlock, "deadlocks: every reachable situation has a way out");
  section(Check::kTransientCycle, "transient cycles: every evaluation reaches stability");
  section(Check::kRoundBound, "transient length: at most " + std::to_string(r.longest_transient) +
                                  " rounds per evaluation (engine bound " +
                                  std::to_string(r.max_rounds) + ")");
  auto invariant_fail = by_check.find(Check::kInvariant);
  for (const InvariantResult& inv : r.invariants) {
    const Violation* failed = nullptr;
    if (invariant_fail != by_check.end())
      for (const Violation* v : invariant_fail->second)
        if (v->subject == "invariant \"" + inv.name + "\"" && v->where.line == inv.where.line)
          failed = v;
    if (failed == nullptr) {
      out += std::string(inv.held ? "  ok    " : "  FAIL  ") + "invariant \"" + inv.name + "\"" +
             line_of(inv.where) + ": " + (inv.held ? "holds" : "violated") + " on " +
             std::to_string(inv.evaluations) + " evolutions\n";
      continue;
    }
    out += "  FAIL  invariant \"" + inv.name + "\"" + line_of(inv.where) + "\n        " +
           failed->detail + "\n";
    path_text(out, g, r, *failed);
  }
  for (const std::string& n : r.notes) out += "  note  " + n + "\n";
  if (r.violations_dropped != 0)
    out += "  (" + std::to_string(r.violations_dropped) + " further violations not shown)\n";
  const std::size_t total = r.violations.size() + r.violations_dropped;
  out += total == 0
             ? "\nPASS: no violation\n"
             : "\nFAIL: " + std::to_string(total) + (total == 1 ? " violation\n" : " violations\n");
  return out;
}

}  // namespace smc::grafcet
