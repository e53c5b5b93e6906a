#pragma once
// The band a model's small-signal gain must lie in (gain_plausibility.hpp says why), as each
// model's descriptor computes and refuses it.

#include <string>
#include <string_view>

#include "models/linear.hpp"

namespace hystloop {

struct GainPlausibility {
  double nominal_gain_m_per_V = LinearParams{}.gain;  // the stage's mean slope dy/du
  double factor = 10.0;                               // [-] gains within [nominal / factor, nominal * factor]
  double u_min_V = -250.0;                            // the actuator's range: where a model is used
  double u_max_V = 250.0;

  // Throws ParameterError: nominal_gain_m_per_V > 0, factor in [kMinFactor, kMaxFactor],
  // u_max_V > u_min_V, all finite.
  void validate() const;
  double min_gain_m_per_V() const noexcept { return nominal_gain_m_per_V / factor; }
  double max_gain_m_per_V() const noexcept { return nominal_gain_m_per_V * factor; }

  static constexpr double kMinFactor = 2.0;  // below, hysteresis alone leaves the band
  static constexpr double kMaxFactor = 1e4;
};

// The smallest and largest small-signal gain of a valid set over the actuator's range [m/V].
struct GainRange {
  double min_m_per_V = 0.0;
  double max_m_per_V = 0.0;
};
// For the models' refuse_gain: ParameterError(field, "<what> is <gain> m/V, below|above the
// plausible [lo, hi] m/V ...").
[[noreturn]] void refuse_implausible_gain(std::string_view field, const std::string& what, double gain_m_per_V,
                                          bool low, const GainPlausibility& rig);
// A number as the refusals print it ("%.6g").
std::string refusal_number(double v);

}  // namespace hystloop
