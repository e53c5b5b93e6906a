#include "ident/params_yaml.hpp"

#include <cstdio>
#include <sstream>

namespace hystloop {
namespace {

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string shaping(const ShapingFunction& s) {
  std::ostringstream o;
  switch (s.kind) {
    case ShapingKind::linear:
      o << "{kind: linear, gain: " << num(s.gain) << ", offset: " << num(s.offset) << "}";
      break;
    case ShapingKind::polynomial: {
      std::size_t n = ShapingFunction::kMaxCoefficients;
      while (n > 1 && s.coefficients[n - 1] == 0.0) --n;
      o << "{kind: polynomial, coefficients: [";
      for (std::size_t i = 0; i < n; ++i) o << (i ? ", " : "") << num(s.coefficients[i]);
      o << "], domain_min: " << num(s.domain_min) << ", domain_max: " << num(s.domain_max) << "}";
      break;
    }
    case ShapingKind::tanh:
      o << "{kind: tanh, amplitude: " << num(s.amplitude) << ", scale: " << num(s.scale)
        << ", offset: " << num(s.offset) << "}";
      break;
  }
  return o.str();
}

}  // namespace

std::string to_yaml(const MemParams& p) {
  return "mem:\n  c1: " + num(p.c1) + "  # [m/V]\n  c2: " + num(p.c2) + "  # [m/V^(1+c3)]\n  c3: " + num(p.c3) + "\n";
}

std::string to_yaml(const PiParams& p) {
  std::ostringstream o;
  o << "pi:\n  count: " << p.count << "\n  thresholds: [";
  for (std::size_t i = 0; i < p.count; ++i) o << (i ? ", " : "") << num(p.thresholds[i]);
  o << "]  # [V]\n  weights: [";
  for (std::size_t i = 0; i < p.count; ++i) o << (i ? ", " : "") << num(p.weights[i]);
  o << "]  # [m/V]\n";
  return o.str();
}

std::string to_yaml(const LinearParams& p) {
  return "linear:\n  gain: " + num(p.gain) + "  # [m/V]\n  offset: " + num(p.offset) + "  # [m]\n";
}

std::string to_yaml(const KatalenicParams& p) {
  std::ostringstream o;
  o << "katalenic:\n  k1: " << num(p.k1) << "  # [V]\n  k2: " << num(p.k2)
    << "  # [1/V]\n  k2_slope: " << num(p.k2_slope) << "\n  initial_offset: " << num(p.initial_offset)
    << "\n  input_shaping: " << shaping(p.input_shaping) << "\n  output_shaping: " << shaping(p.output_shaping) << "\n";
  return o.str();
}

std::string to_yaml(const ColemanHodgdonParams& h, const SecondOrderStageParams* stage) {
  std::ostringstream o;
  o << "banning:\n  hysteresis:\n    a: " << num(h.a) << "  # [m/V]\n    b: " << num(h.b)
    << "  # [m/V]\n    alpha: " << num(h.alpha) << "  # [1/V]\n    s_max: " << num(h.s_max)
    << "  # [V] (not identified)\n";
  if (stage != nullptr) {
    o << "  stage:\n    k: " << num(stage->k) << "  # [1/s^2]\n    c: " << num(stage->c) << "  # [1/s]\n";
    // The same stage for the compensator, which inverts it (hystloop-compensator --params FILE
    // reads this section and leaves the bridge's banning section to the bridge).
    o << "stage:\n  kind: second_order\n  k: " << num(stage->k) << "  # [1/s^2]\n  c: " << num(stage->c)
      << "  # [1/s]\n  order: hysteresis_then_stage\n";
  }
  return o.str();
}

}  // namespace hystloop
