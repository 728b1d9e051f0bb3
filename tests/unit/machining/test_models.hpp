#pragma once
// Models shared by the machining tests.

#include <cmath>
#include <numbers>

#include "smc/machining/model.hpp"
#include "smc/machining/paper_case.hpp"

namespace smc::machining::test {

// The paper's case with a structure so stiff that vibration is negligible
// (forces then follow A1-A4 with the nominal chip).
inline MillingModel rigid_paper_case() {
  MillingModel m = paper_case();
  for (auto* axis :
       {&m.structure.tool_x, &m.structure.tool_y, &m.structure.part_x, &m.structure.part_y}) {
    for (Mode& mode : *axis) mode.stiffness_n_per_mm = 1e12;
  }
  return m;
}

// The one-degree-of-freedom milling model of Insperger & Stepan's
// semi-discretization papers (see benchmark_test.cpp for the source): two
// straight teeth, linear law K_t = 6e8 N/m^2, K_n = 2e8 N/m^2, the tool
// flexible along the feed only, f_n = 922 Hz, zeta = 0.011, m = 0.03993 kg.
// radial_immersion = a/D; down-milling unless slotting (a/D = 1).
inline MillingModel insperger_1dof(double radial_immersion) {
  MillingModel m;
  m.name = "insperger_stepan_1dof";
  const double radius = 10.0;  // mm; only a/D matters
  const double width = 2 * radius * radial_immersion;
  m.cutter = Cutter{2, radius, 0.0};
  m.workpiece = Workpiece{width, radial_immersion >= 1 ? 0.0 : -(radius - width / 2), 100.0,
                          radial_immersion < 1};
  m.law = LinearLaw{600.0, 200.0, 0.0};  // N/mm^2 = 1e6 N/m^2
  const double wn = 2 * std::numbers::pi * 922.0;
  const double mass_kg = 0.03993;
  m.structure.tool_x = {Mode{wn, 0.011, mass_kg * wn * wn / 1000.0}};  // N/mm
  return m;
}

}  // namespace smc::machining::test
