#pragma once
// Whether a parameter set describes this rig's stage at all, before it can reach the actuator.
// A set can lie inside its model's domain (ModelParamSet::validate) and still be absurd: a units
// error (y in mm: every gain 1000x), a corrupted or forged set (MEM c2 = 1e300, c1 = 2.9e-322), a
// fit that ran off. Its inverse would then command volts for metres that are not this stage's.
//
// The test: the model's small-signal gain dy/du, anywhere on a branch the actuator can run (from
// a reversal over up to the whole range u_max_V - u_min_V), must lie within
//   [nominal_gain_m_per_V / factor, nominal_gain_m_per_V * factor],
// the nominal gain being the stage's mean slope the configuration already states (the linear
// model's gain, which the servo's nominal_gain_m_per_V also is). factor = 10 by default: on
// Banning's stage the hysteresis moves the local slope between 0.57 and 1.36 x the mean, the MEM
// fit keeps c1 >= 0.25 x the data's mean slope, and the deployed and demo sets lie within
// 0.19-2.2 x the nominal gain; 10 leaves room for a different stage and still refuses a
// factor-1000 units error by two decades.
//
// Each model's descriptor gives its gain range over p in [0, R], R = u_max_V - u_min_V:
//   MEM        c1 .. c1 + c2 R^c3 (M(p) = c1 + c2 p^c3 grows with p)
//   PI         the cumulative weights w_0 + ... + w_i of the plays a branch or the initial loading
//              curve can engage within the range (r_i < R; the last one is the sum of the weights)
//   linear     its gain
//   Katalenic  psi_out' x H' x psi_in', with H' in [1 / (1 + 2 k1 k2_max), 1] (the inverse
//              operator's dv/du = 1 + M* k2 e^(-k2 u), M* in [0, 2 k1]) and the shaping slopes
//              sampled over the input range and the output band it maps to (+- k1)
// Every parameter must also be 0 or a normal double: no physical quantity is below 2.2e-308 in
// SI units, and arithmetic on subnormals is slow enough to cost a 100 us tick.

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

struct ModelParamSet;  // models/model_set.hpp, which includes this header
GainRange small_signal_gain(const ModelParamSet& set, const GainPlausibility& rig) noexcept;

// Validates the set's model (ModelParamSet::validate, the stage left out: it has no gain), then
// refuses a subnormal parameter or a gain outside the band: ParameterError naming the field
// ("mem.c2", "pi.weights[3]", "linear.gain", "katalenic.output_shaping"), its value, the bound
// and why.
void require_plausible(const ModelParamSet& set, const GainPlausibility& rig);

}  // namespace hystloop
