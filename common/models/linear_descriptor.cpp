// The linear model's parameter table and its gain band.
#include "models/model_set.hpp"

#include "models/param_fields.hpp"

namespace hystloop {

std::span<const ParamSpec<LinearParams>> LinearDescriptor::table() {
  static const ParamSpec<LinearParams> rows[] = {
      summarised(number<LinearParams>(
          "gain", "m/V", "slope (default: chord of the default MEM's +-250 V loop)",
          [](auto& p) -> auto& { return p.gain; })),
      summarised(number<LinearParams>(
          "offset", "m", "output at u = 0", [](auto& p) -> auto& { return p.offset; })),
  };
  return rows;
}

GainRange LinearDescriptor::gain_range(const LinearParams& p, const GainPlausibility&) noexcept {
  return {p.gain, p.gain};
}

void LinearDescriptor::refuse_gain(const LinearParams& p, const GainRange&, const GainPlausibility& rig) {
  refuse_implausible_gain("gain", "the gain", p.gain, !(p.gain >= rig.min_gain_m_per_V()), rig);
}

}  // namespace hystloop
