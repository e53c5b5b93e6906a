#pragma once
// Shaping functions of the Katalenic operator (paper §4.3): smooth, strictly increasing maps
// applied outside the hysteresis operator, so they bend its affine asymptotes without touching
// its invertibility. One value type, no virtual call: the kind selects the formula.
//
//   linear      psi(x) = gain * x + offset
//   polynomial  psi(x) = sum_i c[i] * x^i on [domain_min, domain_max]; outside the domain it
//               continues along its end tangent, so psi is strictly increasing on all of R and
//               its inverse never fails (validate() proves psi' > 0 on the domain).
//   tanh        psi(x) = offset + amplitude * tanh(x / scale); the inverse saturates: requests
//               beyond the range (offset +- amplitude) map to +-kTanhInverseLimit * scale.
//
// Units: coefficients carry the units of the map they sit on. On the model's input side psi maps
// volts to operator units, on the output side operator units to metres (see katalenic.hpp).

#include <array>
#include <cstddef>
#include <initializer_list>
#include <string_view>

namespace hystloop {

enum class ShapingKind { linear, polynomial, tanh };

struct ShapingFunction {
  static constexpr std::size_t kMaxCoefficients = 8;  // polynomial degree <= 7
  // The tanh inverse clamps (y - offset) / amplitude to +-(1 - 1e-12): atanh of that is 14.16,
  // so it never returns more than this many scales.
  static constexpr double kTanhInverseLimit = 14.2;

  ShapingKind kind = ShapingKind::linear;
  double gain = 1.0;                                    // linear: slope
  double offset = 0.0;                                  // linear, tanh: value at x = 0
  std::array<double, kMaxCoefficients> coefficients{};  // polynomial: c[0] + c[1] x + ...
  double domain_min = -1.0;                             // polynomial: where monotonicity is proven
  double domain_max = 1.0;
  double amplitude = 1.0;  // tanh: half the output range
  double scale = 1.0;      // tanh: input scale (x units)

  static ShapingFunction make_linear(double gain, double offset = 0.0);
  static ShapingFunction make_polynomial(std::initializer_list<double> coefficients, double domain_min,
                                         double domain_max);
  // Odd polynomial from its odd coefficients c1, c3, c5, ...: c1 x + c3 x^3 + ...
  static ShapingFunction make_odd_polynomial(std::initializer_list<double> odd_coefficients, double domain_min,
                                             double domain_max);
  static ShapingFunction make_tanh(double amplitude, double scale, double offset = 0.0);

  // Throws ParameterError naming "<field>.<member>" unless psi is finite and strictly increasing.
  void validate(std::string_view field) const;

  double apply(double x) const noexcept;
  double derivative(double x) const noexcept;
  double second_derivative(double x) const noexcept;
  // psi^{-1}(y). `hint` seeds the polynomial Newton iteration (e.g. the previous solution).
  double invert(double y, double hint = 0.0) const noexcept;
  // An upper bound of psi' over the domain (polynomial) or all of R: scales error bounds.
  double max_slope() const noexcept;
};

}  // namespace hystloop
