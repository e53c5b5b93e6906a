// Parameter table of katalenic, and its gain band: the operator's k1, k2 (and its input-dependent schedule), the
// initial offset, and the two shaping functions field by field ("input_shaping.gain", ...), the
// flattened form of the YAML hystloop-identify writes (input_shaping: {kind: linear, gain: ...}).
#include <algorithm>
#include <array>
#include <deque>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/model_set.hpp"
#include "models/param_fields.hpp"

namespace hystloop {
namespace {

using P = KatalenicParams;

// The rows' names outlive make_rows(): a deque never moves what it holds.
std::string_view stored(std::string name) {
  static std::deque<std::string> names;
  return names.emplace_back(std::move(name));
}

// Whether a shaping field means anything for the function's kind (the YAML written leaves the
// others out: {kind: linear, gain: ..., offset: ...}).
template <class Sel, ShapingKind... kinds>
bool of_kind(const P& p) {
  return ((Sel{}(p).kind == kinds) || ...);
}

// Sel: captureless generic lambda returning the ShapingFunction inside P.
template <class Sel>
void add_shaping_rows(std::vector<ParamSpec<P>>& rows, const std::string& prefix, std::string_view map) {
  const auto n = [&](const char* field) { return stored(prefix + "." + field); };
  rows.push_back(custom<P>(
      n("kind"), "-", map == "in" ? "input map V -> operator units" : "output map operator units -> m",
      ValueKind::choice,
      [](P& p, const ParsedValue& v) {
        Sel{}(p).kind = v.choice == "tanh"         ? ShapingKind::tanh
                        : v.choice == "polynomial" ? ShapingKind::polynomial
                                                   : ShapingKind::linear;
      },
      [](const P& p) {
        switch (Sel{}(p).kind) {
          case ShapingKind::polynomial: return std::string("polynomial");
          case ShapingKind::tanh: return std::string("tanh");
          case ShapingKind::linear: break;
        }
        return std::string("linear");
      },
      "linear|polynomial|tanh"));
  const std::string_view unit = map == "in" ? "x/V" : "m/x";
  rows.push_back(number<P>(
      n("gain"), unit, "linear: slope", [](auto& p) -> auto& { return Sel{}(p).gain; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::linear>;
  rows.push_back(number<P>(
      n("offset"), map == "in" ? "x" : "m", "linear, tanh: value at 0",
      [](auto& p) -> auto& { return Sel{}(p).offset; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::linear, ShapingKind::tanh>;
  rows.push_back(custom<P>(
      n("coefficients"), "-", "polynomial: c0,c1,...,c7 (units of the map)", ValueKind::list,
      [](P& p, const ParsedValue& v) {
        auto& c = Sel{}(p).coefficients;
        if (v.list.size() > c.size()) {
          throw std::invalid_argument("at most " + std::to_string(c.size()) + " coefficients (degree 7), got " +
                                      std::to_string(v.list.size()));
        }
        c.fill(0.0);
        for (std::size_t i = 0; i < v.list.size(); ++i) c[i] = v.list[i];
      },
      [](const P& p) {
        const auto& c = Sel{}(p).coefficients;
        std::size_t k = c.size();
        while (k > 1 && c[k - 1] == 0.0) --k;
        return format_list(std::span<const double>(c.data(), k));
      }));
  rows.back().applies = &of_kind<Sel, ShapingKind::polynomial>;
  rows.push_back(number<P>(
      n("domain_min"), map == "in" ? "V" : "x", "polynomial: lower end of the proven-monotone domain",
      [](auto& p) -> auto& { return Sel{}(p).domain_min; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::polynomial>;
  rows.push_back(number<P>(
      n("domain_max"), map == "in" ? "V" : "x", "polynomial: upper end of that domain",
      [](auto& p) -> auto& { return Sel{}(p).domain_max; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::polynomial>;
  rows.push_back(number<P>(
      n("amplitude"), map == "in" ? "x" : "m", "tanh: half the output range",
      [](auto& p) -> auto& { return Sel{}(p).amplitude; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::tanh>;
  rows.push_back(number<P>(
      n("scale"), map == "in" ? "V" : "x", "tanh: input scale", [](auto& p) -> auto& { return Sel{}(p).scale; }));
  rows.back().applies = &of_kind<Sel, ShapingKind::tanh>;
}

std::vector<ParamSpec<P>> make_rows() {
  std::vector<ParamSpec<P>> rows = {
      summarised(number<P>(
          "k1", "x", "half-width of the backlash band |z - x| <= k1", [](auto& p) -> auto& { return p.k1; })),
      summarised(number<P>(
          "k2", "1/x", "rate of the transition to the asymptotes", [](auto& p) -> auto& { return p.k2; })),
      summarised(number<P>(
          "k2_slope", "1/x^2", "k2(x) = k2 + k2_slope*clamp(x, k2_domain_min, k2_domain_max)",
          [](auto& p) -> auto& { return p.k2_slope; })),
      number<P>(
          "k2_domain_min", "x", "working interval of that schedule, lower end",
          [](auto& p) -> auto& { return p.k2_domain_min; }),
      number<P>(
          "k2_domain_max", "x", "working interval, upper end", [](auto& p) -> auto& { return p.k2_domain_max; }),
      number<P>(
          "initial_offset", "x", "z - x at reset, |.| <= k1", [](auto& p) -> auto& { return p.initial_offset; }),
  };
  add_shaping_rows<decltype([](auto& p) -> auto& { return p.input_shaping; })>(rows, "input_shaping", "in");
  add_shaping_rows<decltype([](auto& p) -> auto& { return p.output_shaping; })>(rows, "output_shaping", "out");
  return rows;
}

}  // namespace

std::span<const ParamSpec<KatalenicParams>> KatalenicDescriptor::table() {
  static const std::vector<ParamSpec<P>> rows = make_rows();
  return rows;
}

namespace {

// Sample points of a shaping function's slope over an interval (its ends included): enough to
// see a tanh or a degree-7 polynomial bend, cheap at the rate parameter sets arrive.
constexpr int kShapingSamples = 65;

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

// The range of the operator's own slope dz/dx: the inverse operator's dv/du = 1 + M* k2 e^(-k2 u)
// with M* in [0, 2 k1] puts it in [1 / (1 + 2 k1 k2_max), 1].
GainRange operator_slope(const KatalenicParams& k) noexcept { return {1.0 / (1.0 + 2.0 * k.k1 * k.k2_max()), 1.0}; }

}  // namespace

// psi_out' x H' x psi_in', the shaping slopes sampled over the input range and the output band it
// maps to (+- k1).
GainRange KatalenicDescriptor::gain_range(const KatalenicParams& k, const GainPlausibility& rig) noexcept {
  const GainRange in = shaping_slope(k.input_shaping, rig.u_min_V, rig.u_max_V);
  const double x_lo = k.input_shaping.apply(rig.u_min_V), x_hi = k.input_shaping.apply(rig.u_max_V);
  const GainRange out = shaping_slope(k.output_shaping, x_lo - k.k1, x_hi + k.k1);
  const GainRange op = operator_slope(k);
  return {in.min_m_per_V * op.min_m_per_V * out.min_m_per_V, in.max_m_per_V * op.max_m_per_V * out.max_m_per_V};
}

// The operator's own slope right after a reversal is the factor 1 / (1 + 2 k1 k2); when it alone
// leaves the band the transition is the fault, otherwise the output's scale.
void KatalenicDescriptor::refuse_gain(const KatalenicParams& k, const GainRange& g, const GainPlausibility& rig) {
  const bool low = !(g.min_m_per_V >= rig.min_gain_m_per_V());
  const bool operator_fault = low && operator_slope(k).min_m_per_V < 1.0 / rig.factor;
  refuse_implausible_gain(operator_fault ? "k2" : "output_shaping",
                          low ? "the slope right after a reversal" : "the largest slope of a branch",
                          low ? g.min_m_per_V : g.max_m_per_V, low, rig);
}

}  // namespace hystloop
