// MEM's parameter table (names are MemParams' members: the YAML keys hystloop-identify writes and
// the compensator's config keys) and its gain band.
#include "models/model_set.hpp"

#include "models/param_fields.hpp"

namespace hystloop {

std::span<const ParamSpec<MemParams>> MemDescriptor::table() {
  static const ParamSpec<MemParams> rows[] = {
      summarised(number<MemParams>(
          "c1", "m/V", "slope right after a reversal, M(0) = c1", [](auto& p) -> auto& { return p.c1; })),
      summarised(number<MemParams>(
          "c2", "m/V^(1+c3)", "growth of the slope with the distance p from the reversal",
          [](auto& p) -> auto& { return p.c2; })),
      summarised(number<MemParams>(
          "c3", "-", "exponent of that growth, M(p) = c1 + c2 p^c3", [](auto& p) -> auto& { return p.c3; })),
  };
  return rows;
}

// M(p) = c1 + c2 p^c3 grows with p: c1 right after a reversal, c1 + c2 R^c3 across the range.
GainRange MemDescriptor::gain_range(const MemParams& p, const GainPlausibility& rig) noexcept {
  return {p.c1, p.slope(rig.u_max_V - rig.u_min_V)};
}

void MemDescriptor::refuse_gain(const MemParams& p, const GainRange& g, const GainPlausibility& rig) {
  const char* const c1_what = "the slope right after a reversal, c1,";
  if (!(g.min_m_per_V >= rig.min_gain_m_per_V())) refuse_implausible_gain("c1", c1_what, g.min_m_per_V, true, rig);
  if (p.c1 > rig.max_gain_m_per_V()) refuse_implausible_gain("c1", c1_what, p.c1, false, rig);
  refuse_implausible_gain(
      "c2",
      "the slope c1 + c2 p^c3 at p = " + number_text(rig.u_max_V - rig.u_min_V) + " V (the actuator's whole range)",
      g.max_m_per_V, false, rig);
}

}  // namespace hystloop
