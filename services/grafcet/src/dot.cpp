// Graphviz DOT output of a Grafcet.

#include "smc/grafcet/dot.hpp"

#include <algorithm>
#include <bit>

namespace smc::grafcet {
namespace {

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string actions_text(const Grafcet& g, const Step& s) {
  std::string out;
  const Mask all = s.level_actions | s.impulse_actions;
  for (Mask m = all; m != 0; m &= m - 1) {
    const auto i = static_cast<std::size_t>(std::countr_zero(m));
    const Mask bit = Mask{1} << i;
    if ((s.level_actions & bit) != 0) out += (out.empty() ? "" : " | ") + g.actions()[i].name;
    if ((s.impulse_actions & bit) != 0)
      out += (out.empty() ? "" : " | ") + g.actions()[i].name + "*";
  }
  return out;
}

}  // namespace

std::string to_dot(const Grafcet& g) {
  std::string out = "digraph " + quoted(g.name()) + " {\n";
  out += "  graph [rankdir=TB, nodesep=0.5, ranksep=0.35, fontname=\"Helvetica\"";
  if (!g.title().empty()) out += ", label=" + quoted(g.title()) + ", labelloc=t";
  out += "];\n  node [fontname=\"Helvetica\"];\n  edge [arrowhead=none];\n\n";

  const auto steps = g.steps();
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const Step& s = steps[i];
    const std::string id = std::string("s").append(std::to_string(s.number));
    out += "  " + id +
           " [shape=box, width=0.5, height=0.5, label=" + quoted(std::to_string(s.number)) +
           (s.initial ? ", peripheries=2" : "") +
           (s.label.empty() ? "" : ", tooltip=" + quoted(s.label)) + "];\n";
    const std::string acts = actions_text(g, s);
    if (!acts.empty()) {
      out += "  " + id + "_act [shape=record, fontsize=11, label=" + quoted(acts) + "];\n";
      out += "  { rank=same; " + id + "; " + id + "_act; }\n";
      out += "  " + id + " -> " + id + "_act [constraint=false];\n";
    }
  }
  out += "\n";

  const auto orders = g.orders();
  const auto transitions = g.transitions();
  for (std::size_t t = 0; t < transitions.size(); ++t) {
    const Transition& tr = transitions[t];
    std::string label =
        std::string("(").append(std::to_string(tr.number)) + ") " + tr.receptivity.text;
    for (const CheckingOrder& o : orders)
      for (std::size_t k = 0; k < o.transitions.size(); ++k)
        if (o.transitions[k] == t)
          label +=
              "  [" + std::to_string(k + 1) + " from " + std::to_string(steps[o.step].number) + "]";
    const std::string id = std::string("t").append(std::to_string(tr.number));
    out += "  " + id +
           " [shape=box, style=filled, fillcolor=black, width=0.45, height=0.04, label=\"\", "
           "xlabel=" +
           quoted(label) + "];\n";
    for (Mask m = tr.preceding; m != 0; m &= m - 1)
      out += "  s" + std::to_string(steps[static_cast<std::size_t>(std::countr_zero(m))].number) +
             " -> " + id + ";\n";
    for (Mask m = tr.following; m != 0; m &= m - 1) {
      const Step& s = steps[static_cast<std::size_t>(std::countr_zero(m))];
      // Arcs back up the chart carry an arrow, as on the paper's figures.
      const bool upward = s.number <= [&] {
        std::uint32_t lowest = ~0u;
        for (Mask p = tr.preceding; p != 0; p &= p - 1)
          lowest = std::min(lowest, steps[static_cast<std::size_t>(std::countr_zero(p))].number);
        return lowest;
      }();
      out += "  " + id + " -> s" + std::to_string(s.number) +
             (upward ? " [arrowhead=normal, constraint=false]" : "") + ";\n";
    }
  }
  out += "}\n";
  return out;
}

}  // namespace smc::grafcet
