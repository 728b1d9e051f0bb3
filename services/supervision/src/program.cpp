#include "smc/supervision/program.hpp"

#include <cmath>

namespace smc::supervision {

double FixedProgram::total_depth_mm() const noexcept { return depth_before(count); }

double FixedProgram::depth_before(int i) const noexcept {
  double d = 0;
  for (int k = 0; k < i && k < count; ++k) d += passes[static_cast<size_t>(k)].depth_mm;
  return d;
}

bool add_one_pass(FixedProgram& program, int current) noexcept {
  if (current < 0 || current >= program.count || program.count >= FixedProgram::kMaxPasses) {
    return false;
  }
  const auto first = static_cast<size_t>(current);
  const int remaining = program.count - current;
  double depth = 0;
  for (size_t k = first; k < program.count; ++k) depth += program.passes[k].depth_mm;
  const int n = remaining + 1;
  const double each = depth / n;
  const PassSpec tmpl = program.passes[first];
  for (int k = 0; k < n; ++k) {
    PassSpec& p = program.passes[first + static_cast<size_t>(k)];
    // Later passes keep their own feed and speed where they had them.
    if (k >= remaining) p = program.passes[first + static_cast<size_t>(remaining - 1)];
    if (k == 0) p = tmpl;
    p.depth_mm = each;
  }
  program.count = static_cast<uint16_t>(program.count + 1);
  ++program.revision;
  return true;
}

}  // namespace smc::supervision
