#include "models/gain_plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/errors.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {
namespace {

// Sample points of a shaping function's slope over an interval (its ends included): enough to
// see a tanh or a degree-7 polynomial bend, cheap at the rate parameter sets arrive.
constexpr int kShapingSamples = 65;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void require_normal(const std::string& field, double value) {
  if (std::fpclassify(value) == FP_SUBNORMAL) {
    throw ParameterError(field, "is " + num(value) +
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

// The smallest and largest slope of a shaping function over [lo, hi].
GainRange shaping_slope(const ShapingFunction& s, double lo, double hi) noexcept {
  if (s.kind == ShapingKind::linear) return {s.gain, s.gain};
  GainRange r{s.derivative(lo), s.derivative(lo)};
  for (int i = 1; i < kShapingSamples; ++i) {
    const double x = lo + (hi - lo) * static_cast<double>(i) / (kShapingSamples - 1);
    const double d = s.derivative(x);
    r.min_m_per_V = std::min(r.min_m_per_V, d);
    r.max_m_per_V = std::max(r.max_m_per_V, d);
  }
  return r;
}

// The range of the operator's own slope dz/dx (see the header).
GainRange katalenic_operator_slope(const KatalenicParams& k) noexcept {
  return {1.0 / (1.0 + 2.0 * k.k1 * k.k2_max()), 1.0};
}

// The plays a branch or the initial loading curve can engage within a range of R volts.
std::size_t engaged_plays(const PiParams& pi, double range_V) noexcept {
  std::size_t n = 0;
  while (n < pi.count && n < kPiMaxOperators && pi.thresholds[n] < range_V) ++n;
  return std::max<std::size_t>(n, 1);  // r_0 = 0: the identity always is
}

std::string band(const GainPlausibility& rig) {
  return "[" + num(rig.min_gain_m_per_V()) + ", " + num(rig.max_gain_m_per_V()) + "] m/V (the nominal gain " +
         num(rig.nominal_gain_m_per_V) + " m/V within a factor " + num(rig.factor) + ")";
}

[[noreturn]] void refuse(const std::string& field, const std::string& what, double gain, bool low,
                         const GainPlausibility& rig) {
  throw ParameterError(field, what + " is " + num(gain) + " m/V, " + (low ? "below" : "above") + " the plausible " +
                                  band(rig) + ": not this stage's gain (a units error, or a corrupted set)");
}

}  // namespace

void GainPlausibility::validate() const {
  require_positive("nominal_gain_m_per_V", nominal_gain_m_per_V);
  require_in_range("factor", factor, kMinFactor, kMaxFactor);
  require_finite("u_min_V", u_min_V);
  require_finite("u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("u_max_V", "must be greater than u_min_V");
}

GainRange small_signal_gain(const ModelParamSet& set, const GainPlausibility& rig) noexcept {
  const double range_V = rig.u_max_V - rig.u_min_V;
  switch (set.kind) {
    case ModelKind::mem: return {set.mem.c1, set.mem.slope(range_V)};
    case ModelKind::linear: return {set.linear.gain, set.linear.gain};
    case ModelKind::pi: {
      const std::size_t n = engaged_plays(set.pi, range_V);
      GainRange r{set.pi.weights[0], set.pi.weights[0]};
      double cumulative = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        cumulative += set.pi.weights[i];
        r.min_m_per_V = std::min(r.min_m_per_V, cumulative);
        r.max_m_per_V = std::max(r.max_m_per_V, cumulative);
      }
      return r;
    }
    case ModelKind::katalenic: {
      const KatalenicParams& k = set.katalenic;
      const GainRange in = shaping_slope(k.input_shaping, rig.u_min_V, rig.u_max_V);
      const double x_lo = k.input_shaping.apply(rig.u_min_V), x_hi = k.input_shaping.apply(rig.u_max_V);
      const GainRange out = shaping_slope(k.output_shaping, x_lo - k.k1, x_hi + k.k1);
      const GainRange op = katalenic_operator_slope(k);
      return {in.min_m_per_V * op.min_m_per_V * out.min_m_per_V, in.max_m_per_V * op.max_m_per_V * out.max_m_per_V};
    }
  }
  return {};
}

void require_plausible(const ModelParamSet& set, const GainPlausibility& rig) {
  ModelParamSet model = set;
  model.stage.reset();  // a unit-gain dynamic stage: nothing to bound here
  model.validate();
  require_normal_parameters(model);
  const GainRange g = small_signal_gain(model, rig);
  const double lo = rig.min_gain_m_per_V(), hi = rig.max_gain_m_per_V();
  const bool low = !(g.min_m_per_V >= lo), high = !(g.max_m_per_V <= hi);
  if (!low && !high) return;
  const std::string range = num(rig.u_max_V - rig.u_min_V);
  switch (model.kind) {
    case ModelKind::mem:
      if (low) refuse("mem.c1", "the slope right after a reversal, c1,", g.min_m_per_V, true, rig);
      if (model.mem.c1 > hi) refuse("mem.c1", "the slope right after a reversal, c1,", model.mem.c1, false, rig);
      refuse("mem.c2", "the slope c1 + c2 p^c3 at p = " + range + " V (the actuator's whole range)", g.max_m_per_V,
             false, rig);
    case ModelKind::linear: refuse("linear.gain", "the gain", low ? g.min_m_per_V : g.max_m_per_V, low, rig);
    case ModelKind::pi: {
      // Name the first play whose cumulative weight leaves the band.
      const std::size_t n = engaged_plays(model.pi, rig.u_max_V - rig.u_min_V);
      double cumulative = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        cumulative += model.pi.weights[i];
        if (!(cumulative >= lo) || !(cumulative <= hi)) {
          const bool below = !(cumulative >= lo);
          refuse("pi.weights[" + std::to_string(i) + "]",
                 "the slope w_0 + ... + w_" + std::to_string(i) + " of a branch", cumulative, below, rig);
        }
      }
      refuse("pi.weights", "the slope of a branch", low ? g.min_m_per_V : g.max_m_per_V, low, rig);
    }
    case ModelKind::katalenic: {
      const KatalenicParams& k = model.katalenic;
      // The operator's own slope right after a reversal is the factor 1 / (1 + 2 k1 k2); when it
      // alone leaves the band the transition is the fault, otherwise the output's scale.
      const bool operator_fault = low && katalenic_operator_slope(k).min_m_per_V < 1.0 / rig.factor;
      refuse(operator_fault ? "katalenic.k2" : "katalenic.output_shaping",
             low ? "the slope right after a reversal" : "the largest slope of a branch",
             low ? g.min_m_per_V : g.max_m_per_V, low, rig);
    }
  }
  throw ParameterError("kind", "names no model");
}

}  // namespace hystloop
