// Shaping functions (paper §4.3): values, inverses, derivatives, the proven monotonicity check.
#include "models/katalenic_shaping.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {
namespace {

std::vector<ShapingFunction> valid_shapings() {
  return {
      ShapingFunction::make_linear(3.79e-9, 1e-7),
      ShapingFunction::make_tanh(1.2e-6, 300.0, -1e-8),
      ShapingFunction::make_polynomial({0.0, 1.0, -0.098}, -5.0, 5.0),  // the paper's Example 1 psi_input
      ShapingFunction::make_odd_polynomial({1.0, 2e-6, 1e-11}, -300.0, 300.0),
      ShapingFunction::make_polynomial({0.1, 0.9, 0.05, 0.01, -1e-4, 1e-5}, -4.0, 4.0),
  };
}

std::string field_of_error(const ShapingFunction& s) {
  try {
    s.validate("output_shaping");
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "";
}

TEST(ShapingFunction, ValidExamplesPassValidation) {
  for (const auto& s : valid_shapings()) EXPECT_NO_THROW(s.validate("input_shaping"));
}

TEST(ShapingFunction, InverseIsExactInsideAndOutsideTheDomain) {
  std::mt19937_64 rng(11);
  for (const auto& s : valid_shapings()) {
    const double span = s.kind == ShapingKind::polynomial ? 1.5 * std::max(-s.domain_min, s.domain_max)
                                                          : (s.kind == ShapingKind::tanh ? 3.0 * s.scale : 1e3);
    std::uniform_real_distribution<double> x_dist(-span, span);
    for (int i = 0; i < 5000; ++i) {
      const double x = x_dist(rng);
      const double y = s.apply(x);
      const double back = s.invert(y, x_dist(rng));  // arbitrary warm start
      EXPECT_NEAR(back, x, 1e-12 * span / (s.kind == ShapingKind::tanh ? 1e-3 : 1.0)) << "x = " << x;
    }
    EXPECT_TRUE(std::isfinite(s.invert(s.apply(0.3), std::nan(""))));
  }
}

TEST(ShapingFunction, DerivativesMatchFiniteDifferences) {
  for (const auto& s : valid_shapings()) {
    const double span = s.kind == ShapingKind::polynomial ? 0.9 * std::max(-s.domain_min, s.domain_max)
                                                          : (s.kind == ShapingKind::tanh ? 2.0 * s.scale : 1e3);
    for (int i = -20; i <= 20; ++i) {
      const double x = span * i / 20.0;
      const double h = 1e-4 * span;
      const double fd1 = (s.apply(x + h) - s.apply(x - h)) / (2 * h);
      const double fd2 = (s.apply(x + h) - 2 * s.apply(x) + s.apply(x - h)) / (h * h);
      EXPECT_NEAR(s.derivative(x), fd1, 1e-6 * std::abs(s.max_slope()));
      EXPECT_NEAR(s.second_derivative(x), fd2, 1e-4 * std::abs(s.max_slope()) / span + 1e-3 * std::abs(fd2));
      EXPECT_GT(s.derivative(x), 0.0);
    }
  }
}

TEST(ShapingFunction, PolynomialContinuesAlongItsEndTangent) {
  const auto s = ShapingFunction::make_polynomial({0.0, 1.0, -0.098}, -5.0, 5.0);
  const double slope = s.derivative(5.0);
  EXPECT_NEAR(s.apply(6.0), s.apply(5.0) + slope, 1e-12);
  EXPECT_EQ(s.derivative(7.0), slope);
  EXPECT_NEAR(s.invert(s.apply(9.0)), 9.0, 1e-12);
  EXPECT_NEAR(s.invert(s.apply(-9.0)), -9.0, 1e-12);
}

TEST(ShapingFunction, MaxSlopeBoundsTheDerivativeTightly) {
  for (const auto& s : valid_shapings()) {
    double sampled = 0.0;
    const double lo = s.kind == ShapingKind::polynomial ? s.domain_min : -5.0 * s.scale;
    const double hi = s.kind == ShapingKind::polynomial ? s.domain_max : 5.0 * s.scale;
    for (int i = 0; i <= 10000; ++i) sampled = std::max(sampled, s.derivative(lo + (hi - lo) * i / 10000.0));
    EXPECT_GE(s.max_slope(), sampled * (1 - 1e-12));
    EXPECT_LE(s.max_slope(), sampled * 1.01);
  }
}

TEST(ShapingFunction, MonotonicityIsProvenOrRefusedWithTheField) {
  // Paper's Example 1 input shaping x - 0.098 x^2: increasing for x < 1 / 0.196 = 5.10 only.
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 1.0, -0.098}, -5.0, 5.0)), "");
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 1.0, -0.098}, -6.0, 6.0)),
            "output_shaping.coefficients");
  // Odd polynomial x^3 - x dips inside [-1, 1]; x^3 + x does not.
  EXPECT_EQ(field_of_error(ShapingFunction::make_odd_polynomial({-1.0, 1.0}, -1.0, 1.0)),
            "output_shaping.coefficients");
  EXPECT_EQ(field_of_error(ShapingFunction::make_odd_polynomial({1.0, 1.0}, -1.0, 1.0)), "");
  // p' = (x - 0.3)^2 + 1e-6 > 0 everywhere (barely) ...
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 0.09 + 1e-6, -0.3, 1.0 / 3.0}, -2.0, 2.0)), "");
  // ... p' = (x - 0.3)^2 - 1e-6 is negative on a 2e-3 wide interval, which the proof must find.
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 0.09 - 1e-6, -0.3, 1.0 / 3.0}, -2.0, 2.0)),
            "output_shaping.coefficients");
  // Constant, decreasing, non-finite, empty domain.
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({2.0}, -1.0, 1.0)), "output_shaping.coefficients");
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, -1.0}, -1.0, 1.0)), "output_shaping.coefficients");
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 1.0, NAN}, -1.0, 1.0)),
            "output_shaping.coefficients[2]");
  EXPECT_EQ(field_of_error(ShapingFunction::make_polynomial({0.0, 1.0}, 1.0, 1.0)), "output_shaping.domain_max");
  EXPECT_EQ(field_of_error(ShapingFunction::make_linear(0.0)), "output_shaping.gain");
  EXPECT_EQ(field_of_error(ShapingFunction::make_linear(-2.0)), "output_shaping.gain");
  EXPECT_EQ(field_of_error(ShapingFunction::make_tanh(-1.0, 1.0)), "output_shaping.amplitude");
  EXPECT_EQ(field_of_error(ShapingFunction::make_tanh(1.0, 0.0)), "output_shaping.scale");
  EXPECT_EQ(field_of_error(ShapingFunction::make_tanh(1.0, 1.0, INFINITY)), "output_shaping.offset");
  EXPECT_THROW(ShapingFunction::make_polynomial({1, 2, 3, 4, 5, 6, 7, 8, 9}, -1.0, 1.0), ParameterError);
}

TEST(ShapingFunction, TanhInverseSaturatesInsteadOfOverflowing) {
  const auto s = ShapingFunction::make_tanh(1e-6, 200.0);
  EXPECT_NEAR(s.invert(5e-6), 200.0 * std::atanh(1.0 - 1e-12), 1e-9);
  EXPECT_NEAR(s.invert(-5e-6), -200.0 * std::atanh(1.0 - 1e-12), 1e-9);
  EXPECT_LE(std::abs(s.invert(1e-6)) / s.scale, ShapingFunction::kTanhInverseLimit);
}

}  // namespace
}  // namespace hystloop
