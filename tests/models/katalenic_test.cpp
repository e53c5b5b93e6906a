// KatalenicModel / KatalenicInverse in SI units: the paper's Propositions 4.1 and 4.2, the
// piezo-like defaults, re-anchoring in set_params, rates, validation, allocation-free samples.
#include "models/katalenic.hpp"
#include "models/katalenic_bounds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/smooth_signal.hpp"

namespace hystloop {
namespace {

constexpr double kTwoPi = 6.283185307179586;

using testing::smooth_signal;  // tests/support/smooth_signal.hpp

int reversals(const std::vector<double>& s) {
  int count = 0;
  for (std::size_t k = 2; k < s.size(); ++k) count += ((s[k] - s[k - 1]) * (s[k - 1] - s[k - 2]) < 0.0);
  return count;
}

// The default piezo-like loop plus each shaping on input and output (operator units in volts).
std::vector<std::pair<std::string, KatalenicParams>> shaped_params() {
  std::vector<std::pair<std::string, KatalenicParams>> out;
  KatalenicParams p;
  out.emplace_back("linear", p);
  p.input_shaping = ShapingFunction::make_odd_polynomial({1.0, 1e-6}, -300.0, 300.0);
  p.output_shaping = ShapingFunction::make_polynomial({0.0, 3.6e-9, 1.5e-12, 2e-15}, -300.0, 300.0);
  out.emplace_back("polynomial", p);
  p.input_shaping = ShapingFunction::make_tanh(400.0, 500.0);
  p.output_shaping = ShapingFunction::make_tanh(1.2e-6, 450.0);
  out.emplace_back("tanh", p);
  p.input_shaping = ShapingFunction::make_polynomial({2.0, 1.0, -4e-4}, -300.0, 300.0);
  p.output_shaping = ShapingFunction::make_linear(3.79e-9, 2e-7);
  p.initial_offset = -25.0;
  out.emplace_back("general-polynomial-in+offset", p);
  return out;
}

TEST(KatalenicModel, DefaultsArePiezoLike) {
  KatalenicModel model{KatalenicParams{}};
  model.reset(-250.0);
  const int n = 4000;
  std::vector<double> y(n);
  for (int period = 0; period < 3; ++period) {
    for (int k = 0; k < n; ++k) y[k] = model.forward(-250.0 * std::cos(kTwoPi * k / n));
  }
  const double stroke = y[n / 2] - y[0];
  const double opening = y[3 * n / 4] - y[n / 4];  // descending minus ascending at u = 0
  EXPECT_NEAR(stroke, 1.6e-6, 0.02e-6);
  EXPECT_GT(opening / stroke, 0.10);
  EXPECT_LT(opening / stroke, 0.15);
}

// Proposition 4.1: left inverse H^{-1}[H[u]] = u and right inverse H[H^{-1}[y]] = y, for random
// smooth inputs with many reversals, every shaping. Tolerance: 1e-9 V (input), 1e-17 m (output),
// i.e. ~1e-11 of the range; measured worst cases are printed.
TEST(KatalenicProposition41, ExactLeftAndRightInverse) {
  for (const auto& [name, params] : shaped_params()) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      const auto u = smooth_signal(seed, 240.0, 0.0, 20000);
      ASSERT_GT(reversals(u), 40);
      KatalenicModel model(params);
      KatalenicInverse inverse(params);
      model.reset(u[0]);
      inverse.reset(model.output());
      double worst_left = 0.0;
      for (double uk : u) worst_left = std::max(worst_left, std::abs(inverse.inverse(model.forward(uk)) - uk));
      EXPECT_LT(worst_left, 1e-9) << name << " seed " << seed;

      KatalenicModel stroke_probe(params);
      stroke_probe.reset(0.0);
      const double y_span = stroke_probe.forward(200.0) - stroke_probe.forward(-200.0);
      const auto y = smooth_signal(seed + 100, 0.45 * y_span, stroke_probe.output() + 0.5 * y_span, 20000);
      ASSERT_GT(reversals(y), 40);
      inverse.reset(y[0]);
      model.reset(inverse.output());
      double worst_right = 0.0;
      for (double yk : y) worst_right = std::max(worst_right, std::abs(model.forward(inverse.inverse(yk)) - yk));
      EXPECT_LT(worst_right, 1e-17) << name << " seed " << seed;
      if (seed == 1)
        std::printf("[%s] worst |u - H^-1 H u| = %.3g V, worst |y - H H^-1 y| = %.3g m\n", name.c_str(), worst_left,
                    worst_right);
    }
  }
}

// Proposition 4.2: with different initial conditions the tracking error y - y_ref of
// H[H^{-1}[y_ref]] under a periodic reference shrinks at every reversal and vanishes.
TEST(KatalenicProposition42, MismatchedInitialConditionsDecay) {
  KatalenicParams plant;
  plant.initial_offset = -30.0;
  KatalenicParams compensator;
  compensator.initial_offset = 25.0;
  KatalenicModel model(plant);
  KatalenicInverse inverse(compensator);
  const int n = 2000;
  auto y_ref = [](int k) { return 0.5e-6 * std::sin(kTwoPi * k / 2000.0); };  // ~ +-130 V
  inverse.reset(y_ref(0));
  model.reset(inverse.output());
  std::vector<double> at_reversal;
  double previous_max = INFINITY;
  for (int period = 0; period < 8; ++period) {
    double period_max = 0.0;
    for (int k = 1; k <= n; ++k) {
      const int i = period * n + k;
      const double e = model.forward(inverse.inverse(y_ref(i))) - y_ref(i);
      period_max = std::max(period_max, std::abs(e));
      if (i % (n / 2) == n / 4) at_reversal.push_back(std::abs(e));  // sin extrema
    }
    if (period_max > 1e-15) {
      EXPECT_LT(period_max, previous_max) << "period " << period;
    }
    previous_max = period_max;
  }
  ASSERT_GE(at_reversal.size(), 10u);
  EXPECT_GT(at_reversal.front(), 1e-8);  // a real initial error (tens of nm) ...
  for (std::size_t i = 1; i < at_reversal.size(); ++i) {
    if (at_reversal[i - 1] > 1e-15) {
      EXPECT_LT(at_reversal[i], at_reversal[i - 1]) << "reversal " << i;
    }
  }
  EXPECT_LT(at_reversal.back(), 1e-14);  // ... gone to rounding level
}

TEST(KatalenicModel, SetParamsKeepsTheOutputContinuous) {
  for (const auto& [name, params] : shaped_params()) {
    KatalenicModel model(params);
    KatalenicInverse inverse(params);
    model.reset(0.0);
    inverse.reset(model.output());
    for (int k = 0; k < 700; ++k) {
      const double u = 200.0 * std::sin(kTwoPi * k / 1000.0);
      inverse.inverse(model.forward(u));
    }
    // A wider band, another transition rate, a slightly different output gain: the current
    // point stays inside |z - x| <= k1, so no jump is allowed.
    KatalenicParams changed = params;
    changed.k1 = 45.0;
    changed.k2 = 0.02;
    if (changed.output_shaping.kind == ShapingKind::linear) changed.output_shaping.gain *= 1.01;
    const double y_before = model.output();
    const double u_before = model.input();
    model.set_params(changed);
    EXPECT_NEAR(model.forward(u_before), y_before, 1e-21) << name;
    const double ref_before = inverse.reference();
    const double v_before = inverse.output();
    inverse.set_params(changed);
    EXPECT_NEAR(inverse.inverse(ref_before), v_before, 1e-10) << name;
    // ... and both continue as an exact pair.
    double worst = 0.0;
    for (int k = 700; k < 3000; ++k) {
      const double u = 200.0 * std::sin(kTwoPi * k / 1000.0);
      worst = std::max(worst, std::abs(inverse.inverse(model.forward(u)) - u));
    }
    EXPECT_LT(worst, 1e-9) << name;
  }
}

// Narrowing the band below the current distance |z - x| cannot keep the output: it moves to the
// band's edge, exactly by the excess (documented in KatalenicModel::set_params).
TEST(KatalenicModel, SetParamsOutsideTheNewBandMovesToItsEdge) {
  KatalenicParams p;
  p.k2 = 0.1;  // converge to the asymptote within the ascent
  KatalenicModel model(p);
  model.reset(-250.0);
  for (int k = 0; k <= 500; ++k) model.forward(-250.0 + k);  // long ascent: z -> x - k1
  const double x = model.core().memory().last_alpha();
  const double z = model.core().memory().last_beta();
  ASSERT_NEAR(z, x - 40.0, 1e-6);
  p.k1 = 30.0;
  model.set_params(p);
  EXPECT_NEAR(model.core().memory().last_beta(), x - 30.0, 1e-12);
  EXPECT_NEAR(model.forward(250.0), (x - 30.0) * p.output_shaping.gain, 1e-20);
}

TEST(KatalenicModel, NonFiniteInputReturnsNaNAndKeepsTheState) {
  KatalenicModel model{KatalenicParams{}};
  KatalenicInverse inverse{KatalenicParams{}};
  const double y = model.forward(100.0);
  EXPECT_TRUE(std::isnan(model.forward(NAN)));
  EXPECT_TRUE(std::isnan(model.forward(INFINITY)));
  EXPECT_EQ(model.forward(100.0), y);
  inverse.reset(0.0);
  const double u = inverse.inverse(1e-7);
  EXPECT_TRUE(std::isnan(inverse.inverse(NAN)));
  EXPECT_EQ(inverse.inverse(1e-7), u);
  EXPECT_TRUE(std::isnan(inverse.inverse_with_rates(1e-7, NAN, 0.0).u));
}

// Rates through the shaping functions (chain rule on eqs. (7)-(8)) against finite differences.
TEST(KatalenicInverse, RatesMatchFiniteDifferences) {
  for (const auto& [name, params] : shaped_params()) {
    const double h = 1e-5;  // s
    KatalenicModel probe_model(params);
    probe_model.reset(0.0);
    const double y_mid = probe_model.output();
    const double amp = 0.4 * (probe_model.forward(200.0) - probe_model.forward(-200.0));
    auto y = [&](double t) { return y_mid + amp * std::sin(kTwoPi * t); };
    auto y_dot = [&](double t) { return amp * kTwoPi * std::cos(kTwoPi * t); };
    auto y_ddot = [&](double t) { return -amp * kTwoPi * kTwoPi * std::sin(kTwoPi * t); };
    KatalenicInverse inverse(params);
    inverse.reset(y(0.0));
    int checked = 0;
    for (int k = 1; k < 200000; ++k) {
      const double t = k * h;
      const KatalenicRates r = inverse.inverse_with_rates(y(t), y_dot(t), y_ddot(t));
      if (k % 5000 != 0 || std::abs(std::cos(kTwoPi * t)) < 0.2) continue;
      KatalenicInverse probe = inverse;
      const double u1 = probe.inverse(y(t + h));
      const double u2 = probe.inverse(y(t + 2 * h));
      const double fd_rate = (-3.0 * r.u + 4.0 * u1 - u2) / (2 * h);
      const double fd_acc = (r.u - 2.0 * u1 + u2) / (h * h);
      EXPECT_NEAR(r.u_dot, fd_rate, 1e-5 * std::abs(fd_rate) + 1e-3) << name << " t " << t;
      EXPECT_NEAR(r.u_ddot, fd_acc, 2e-3 * std::abs(r.u_ddot) + 2e-2 * std::abs(r.u_dot) + 5.0) << name << " t " << t;
      ++checked;
    }
    EXPECT_GT(checked, 20) << name;
  }
}

TEST(KatalenicModel, PerSampleCallsAllocateNothing) {
  for (const auto& [name, params] : shaped_params()) {
    KatalenicModel model(params);
    KatalenicInverse inverse(params);
    model.reset(0.0);
    inverse.reset(model.output());
    testing::AllocationCounter counter;
    double sink = 0.0;
    for (int k = 0; k < 5000; ++k) {
      const double u = 230.0 * std::sin(kTwoPi * k / 997.0);
      sink += inverse.inverse(model.forward(u));
      sink += inverse.inverse_with_rates(model.output(), 1e-6, 0.0).u_dot;
    }
    EXPECT_EQ(counter.allocations(), 0u) << name;
    EXPECT_TRUE(std::isfinite(sink));
  }
}

// Prop. 4.3: an input-dependent k2 within the invertibility limit keeps the direct operator
// strictly increasing on every branch, and the paper's approximate inverse H^{-1}(k1, phi(u_d))
// tracks within the bound of (12)/(15) with dk2 = sup|phi'| k1.
TEST(KatalenicProposition43, InputDependentK2StaysInvertibleAndWithinTheBound) {
  KatalenicParams p;
  p.k2 = 0.03;
  p.k2_domain_min = -250.0;
  p.k2_domain_max = 250.0;
  // The limit depends on k2_min, which depends on the slope: solve slope = 0.95 * e k2_min / (2 k1).
  const double e = std::exp(1.0);
  p.k2_slope = 0.95 * e * p.k2 / (2.0 * p.k1 + 0.95 * e * 250.0);
  ASSERT_NO_THROW(p.validate());
  KatalenicModel model(p);
  model.reset(-250.0);
  double last_y = model.output(), last_u = -250.0;
  for (int k = 1; k < 40000; ++k) {
    const double u = 250.0 * std::sin(kTwoPi * k / 4000.0 + 0.37 * std::sin(kTwoPi * k / 9000.0) - 1.5707963);
    const double y = model.forward(u);
    if (u != last_u) {
      EXPECT_GT((y - last_y) * (u - last_u), 0.0) << "k " << k;
    }
    last_y = y;
    last_u = u;
  }
  // Compensation error H(k1, phi(x))[H^{-1}(k1, phi(z))[z_d]] - z_d against the bound.
  KatalenicInverse inverse(p);
  const double bound_m = katalenic_input_dependent_k2_bound(p) * p.output_shaping.max_slope();
  inverse.reset(0.0);
  model.reset(inverse.output());
  double worst = 0.0;
  for (int k = 1; k < 40000; ++k) {
    const double y_ref = 0.7e-6 * std::sin(kTwoPi * k / 4000.0) * (0.6 + 0.4 * std::cos(kTwoPi * k / 11000.0));
    worst = std::max(worst, std::abs(model.forward(inverse.inverse(y_ref)) - y_ref));
  }
  std::printf("Prop 4.3: worst compensation error %.3g m, bound %.3g m\n", worst, bound_m);
  EXPECT_GT(worst, 0.0);
  EXPECT_LE(worst, bound_m);
}

TEST(KatalenicParams, ValidationNamesTheField) {
  auto field_of = [](auto mutate) -> std::string {
    KatalenicParams p;
    mutate(p);
    try {
      p.validate();
    } catch (const ParameterError& e) {
      return e.field();
    }
    return "";
  };
  EXPECT_EQ(field_of([](KatalenicParams&) {}), "");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k1 = 0.0; }), "k1");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k1 = -1.0; }), "k1");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k1 = NAN; }), "k1");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k2 = NAN; }), "k2");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k2 = -0.01; }), "k2");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.initial_offset = 41.0; }), "initial_offset");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k2_slope = INFINITY; }), "k2_slope");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.k2_slope = 1e-4; }), "k2_slope");  // beyond e k2_min / (2 k1)
  EXPECT_EQ(field_of([](KatalenicParams& p) {
              p.k2_slope = -1e-4;
              p.k2 = 0.02;
            }),
            "k2_slope");  // k2(250) < 0
  EXPECT_EQ(field_of([](KatalenicParams& p) {
              p.k2_slope = 1e-6;
              p.k2_domain_min = 1.0;
              p.k2_domain_max = 0.0;
            }),
            "k2_domain_max");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.input_shaping = ShapingFunction::make_linear(0.0); }),
            "input_shaping.gain");
  EXPECT_EQ(field_of([](KatalenicParams& p) {
              p.output_shaping = ShapingFunction::make_polynomial({0.0, 1e-9, -1e-11}, -300.0, 300.0);
            }),
            "output_shaping.coefficients");
  EXPECT_EQ(field_of([](KatalenicParams& p) { p.input_shaping = ShapingFunction::make_tanh(1.0, NAN); }),
            "input_shaping.scale");
  // The constructors and set_params refuse too, and a refused set_params changes nothing.
  KatalenicParams bad;
  bad.k1 = -2.0;
  EXPECT_THROW(KatalenicModel{bad}, ParameterError);
  EXPECT_THROW(KatalenicInverse{bad}, ParameterError);
  KatalenicModel model{KatalenicParams{}};
  EXPECT_THROW(model.set_params(bad), ParameterError);
  EXPECT_EQ(model.params().k1, 40.0);
}

}  // namespace
}  // namespace hystloop
