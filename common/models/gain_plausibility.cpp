#include "models/gain_plausibility.hpp"

#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "models/model_set.hpp"

namespace hystloop {
namespace {

void require_normal(const std::string& field, double value) {
  if (std::fpclassify(value) == FP_SUBNORMAL) {
    throw ParameterError(field, "is " + number_text(value) +
                                    ", a subnormal number (below 2.2e-308): no parameter of a stage is that "
                                    "small, and arithmetic on it is slow enough to cost a tick; 0 or a normal value");
  }
}

// Every number of the set, through its model's table: "mem.c1", "pi.weights[3]",
// "katalenic.input_shaping.coefficients[2]".
void require_normal_parameters(const ModelParamSet& set) {
  OnlineModels::visit(set.kind, [&]<class D>() {
    for_each_number(D::table(), D::settings_of(set.*D::in_set),
                    [](const std::string& name, double v) { require_normal(std::string(D::name) + "." + name, v); });
  });
}

std::string band(const GainPlausibility& rig) {
  return "[" + number_text(rig.min_gain_m_per_V()) + ", " + number_text(rig.max_gain_m_per_V()) +
         "] m/V (the nominal gain " + number_text(rig.nominal_gain_m_per_V) + " m/V within a factor " +
         number_text(rig.factor) + ")";
}

}  // namespace

void refuse_implausible_gain(std::string_view field, const std::string& what, double gain_m_per_V, bool low,
                             const GainPlausibility& rig) {
  throw ParameterError(std::string(field), what + " is " + number_text(gain_m_per_V) + " m/V, " +
                                               (low ? "below" : "above") + " the plausible " + band(rig) +
                                               ": not this stage's gain (a units error, or a corrupted set)");
}

void GainPlausibility::validate() const {
  require_positive("nominal_gain_m_per_V", nominal_gain_m_per_V);
  require_in_range("factor", factor, kMinFactor, kMaxFactor);
  require_finite("u_min_V", u_min_V);
  require_finite("u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("u_max_V", "must be greater than u_min_V");
}

GainRange small_signal_gain(const ModelParamSet& set, const GainPlausibility& rig) noexcept {
  GainRange g;
  OnlineModels::visit(set.kind, [&]<class D>() { g = D::gain_range(set.*D::in_set, rig); });
  return g;
}

void require_plausible(const ModelParamSet& set, const GainPlausibility& rig) {
  ModelParamSet model = set;
  model.stage.reset();  // a unit-gain dynamic stage: nothing to bound here
  model.validate();
  require_normal_parameters(model);
  const GainRange g = small_signal_gain(model, rig);
  if (g.min_m_per_V >= rig.min_gain_m_per_V() && g.max_m_per_V <= rig.max_gain_m_per_V()) return;
  OnlineModels::visit(model.kind, [&]<class D>() {
    validate_within(std::string(D::name) + ".", [&] { D::refuse_gain(model.*D::in_set, g, rig); });
  });
  throw ParameterError("kind", "names no model");
}

}  // namespace hystloop
