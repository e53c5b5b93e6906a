#include "loop/feasibility.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/errors.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kGain = 6.4e-9;  // [m/V]: 1 um takes 156.25 V

LinearPlant static_gain() { return {kGain, std::nullopt}; }
LinearPlant with_stage() { return {kGain, SecondOrderStageParams{}}; }  // Banning's Table 2: k 1.17e8, c 2.03e3

using testing::refused_field;

TEST(Feasibility, SineOfAStaticGainByHand) {
  // 1 um at 100 Hz: 2 pi 100 1e-6 / 6.4e-9 = 9.817e4 V/s, twice the 5e4 V/s slew limit.
  const VoltageNeed need = sine_need(static_gain(), 1e-6, 100.0, 0.0);
  EXPECT_NEAR(need.rate_V_per_s, 98174.77042468103, 1e-9);
  EXPECT_NEAR(need.u_max_V, 156.25, 1e-12);
  EXPECT_NEAR(need.u_min_V, -156.25, 1e-12);
  const FeedforwardLimits limits;  // +-250 V, 5e4 V/s
  EXPECT_EQ(exceeded_limit(need, limits), Limit::kSlew);
  EXPECT_STREQ(to_string(exceeded_limit(need, limits)), "slew");
  // At 10 Hz it fits; around an offset of 0.7 um the top reaches 265.6 V.
  EXPECT_TRUE(fits(sine_need(static_gain(), 1e-6, 10.0, 0.0), limits));
  const VoltageNeed offset = sine_need(static_gain(), -1e-6, 10.0, 0.7e-6);
  EXPECT_NEAR(offset.u_max_V, 109.375 + 156.25, 1e-12);
  EXPECT_NEAR(offset.u_min_V, 109.375 - 156.25, 1e-12);
  EXPECT_EQ(exceeded_limit(offset, limits), Limit::kRange);
}

TEST(Feasibility, TheStageInverseGainIsItsExactMagnitude) {
  const LinearPlant plant = with_stage();
  // |k - w^2 + i c w| / k at 100 Hz (w = 628.3 rad/s), by hand: 0.99669.
  EXPECT_NEAR(stage_inverse_gain(plant, 100.0), 0.9966853980599927, 1e-14);
  // At the natural frequency only the damping is left: c w_n / k = 2 zeta.
  const double fn = std::sqrt(plant.stage->k) / (2 * kPi);
  EXPECT_NEAR(stage_inverse_gain(plant, fn), plant.stage->c / std::sqrt(plant.stage->k), 1e-14);
  EXPECT_NEAR(stage_inverse_gain(plant, 0.0), 1.0, 0.0);
  EXPECT_EQ(stage_inverse_gain(static_gain(), 1e3), 1.0);
  const VoltageNeed need = sine_need(plant, 1e-6, 100.0, 0.0);
  EXPECT_NEAR(need.rate_V_per_s, 98174.77042468103 * 0.9966853980599927, 1e-8);
  EXPECT_NEAR(need.u_max_V, 156.25 * 0.9966853980599927, 1e-12);
}

TEST(Feasibility, SharpAndRoundedTrianglesOfAStaticGain) {
  // 1 um at 10 Hz: v = 4 A f = 4e-5 m/s, 6250 V/s; rounding the corners over 10 ms raises the
  // slope to 2A / (T/2 - tau + 2 tau / pi) = 4.3135e-5 m/s. The range stays +-A.
  VoltageNeed need = triangle_need(static_gain(), 1e-6, 10.0, 0.0, 0.0);
  EXPECT_NEAR(need.rate_V_per_s, 6250.0, 1e-9);
  EXPECT_NEAR(need.u_max_V, 156.25, 1e-12);
  need = triangle_need(static_gain(), 1e-6, 10.0, 0.01, 0.0);
  EXPECT_NEAR(need.rate_V_per_s, 4.313487191507935e-05 / kGain, 1e-8);
  EXPECT_NEAR(need.u_max_V, 156.25, 1e-12);
  // With the stage a sharp corner needs an unbounded voltage.
  need = triangle_need(with_stage(), 1e-6, 10.0, 0.0, 0.0);
  EXPECT_TRUE(std::isinf(need.rate_V_per_s));
  EXPECT_EQ(exceeded_limit(need, FeedforwardLimits{}), Limit::kRange);
}

// The triangle's exact peaks against the feedforward computed from the reference itself:
// u = (y + (c/k) y' + y''/k) / g with y', y'' by central differences of evaluate_shape, and du/dt
// by a central difference of u, over the corner (the straight parts need exactly v / g).
TEST(Feasibility, TriangleWithTheStageMatchesTheDifferentiatedReference) {
  const LinearPlant plant = with_stage();
  const double k = plant.stage->k, c = plant.stage->c;
  for (const double corner : {1.5e-4, 4e-4, 3e-3}) {
    TrajectorySpec s;
    s.shape = TrajectoryShape::kTriangle;
    s.amplitude_m = 1e-6;
    s.frequency_hz = 10.0;
    s.corner_s = corner;
    const double h = 1e-7;
    auto y = [&](double t) { return evaluate_shape(s, t); };
    auto u = [&](double t, double step) {
      const double d1 = (y(t + step) - y(t - step)) / (2 * step);
      const double d2 = (y(t + step) - 2 * y(t) + y(t - step)) / (step * step);
      return (y(t) + c / k * d1 + d2 / k) / kGain;
    };
    // The joins too: where the stage's share is small the top is at the corner's start, where the
    // jerk jumps and a central difference is O(step jerk / k) off: there the finer step.
    double u_max = std::max(u(0.025 - corner / 2, 1e-8), u(0.025 + corner / 2, 1e-8)), rate_max = 0.0;
    for (double t = 0.025 - corner; t < 0.025 + corner; t += corner / 4000) {
      u_max = std::max(u_max, u(t, h));
      rate_max = std::max(rate_max, std::abs(u(t + h, h) - u(t - h, h)) / (2 * h));
    }
    const VoltageNeed need = voltage_need(plant, s);
    EXPECT_NEAR(need.u_max_V, u_max, 1e-6 * u_max) << corner;
    EXPECT_NEAR(need.u_min_V, -need.u_max_V, 1e-12) << corner;
    EXPECT_NEAR(need.rate_V_per_s, rate_max, 2e-3 * rate_max) << corner;
    // The looser bound v (1 + (c/k) pi / tau + pi^2 / (k tau^2)) / g lies above it.
    const double v = triangle_slope_m_per_s(s);
    const double bound = v * (1 + c / k * kPi / corner + kPi * kPi / (k * corner * corner)) / kGain;
    EXPECT_LE(need.rate_V_per_s, bound * (1 + 1e-15)) << corner;
    EXPECT_GE(need.rate_V_per_s, v / kGain * (1 - 1e-15)) << corner;
  }
}

TEST(Feasibility, UsableLimitsShrinkAboutTheCentre) {
  FeedforwardLimits l{-50.0, 150.0, 4e4, 0.8};
  l.validate();
  EXPECT_NEAR(l.usable_min_V(), -30.0, 1e-12);
  EXPECT_NEAR(l.usable_max_V(), 130.0, 1e-12);
  EXPECT_NEAR(l.usable_slew_V_per_s(), 3.2e4, 1e-9);
  EXPECT_EQ(exceeded_limit({-30.0, 130.0, 3.2e4}, l), Limit::kNone);  // the limits themselves fit
  EXPECT_EQ(exceeded_limit({-30.1, 0.0, 0.0}, l), Limit::kRange);
  EXPECT_EQ(exceeded_limit({0.0, 0.0, 3.21e4}, l), Limit::kSlew);
  EXPECT_EQ(exceeded_limit({0.0, 200.0, 1e9}, l), Limit::kRange);  // range is named first
  EXPECT_EQ(refused_field([] { FeedforwardLimits{10.0, 10.0, 1.0, 1.0}.validate(); }), "limits.u_max_V");
  EXPECT_EQ(refused_field([] { FeedforwardLimits{-1.0, 1.0, 0.0, 1.0}.validate(); }), "limits.slew_V_per_s");
  EXPECT_EQ(refused_field([] { FeedforwardLimits{-1.0, 1.0, 1.0, 0.0}.validate(); }), "limits.fraction");
  EXPECT_EQ(refused_field([] { FeedforwardLimits{-1.0, 1.0, 1.0, 1.5}.validate(); }), "limits.fraction");
  EXPECT_EQ(refused_field([] { LinearPlant{0.0, std::nullopt}.validate(); }), "plant.gain_m_per_V");
  EXPECT_EQ(refused_field([] { LinearPlant{1e-8, SecondOrderStageParams{1e8, -1.0}}.validate(); }), "plant.stage.c");
  EXPECT_EQ(refused_field([] { triangle_need(static_gain(), 1e-6, 10.0, 0.05, 0.0); }), "corner_s");
  EXPECT_EQ(refused_field([] { sine_need(static_gain(), 1e-6, 0.0, 0.0); }), "frequency_hz");
}

TEST(Feasibility, LargestSineAmplitudeByHand) {
  const FeedforwardLimits limits;
  // 100 Hz: the slew limit, g S / w = 6.4e-9 5e4 / 628.3 = 0.5093 um (the range would allow 1.6 um).
  double a = largest_sine_amplitude_m(static_gain(), limits, 100.0, 0.0);
  EXPECT_NEAR(a, 5.092958178940651e-07, 1e-20);
  EXPECT_NEAR(sine_need(static_gain(), a, 100.0, 0.0).rate_V_per_s, 5e4, 1e-9);
  // 1 Hz: the range, 250 V x g; around 1 um of offset only 250 - 156.25 V are left.
  EXPECT_NEAR(largest_sine_amplitude_m(static_gain(), limits, 1.0, 0.0), 1.6e-6, 1e-20);
  EXPECT_NEAR(largest_sine_amplitude_m(static_gain(), limits, 1.0, 1e-6), 93.75 * kGain, 1e-20);
  EXPECT_EQ(largest_sine_amplitude_m(static_gain(), limits, 1.0, 2e-6), 0.0);  // 312.5 V: the offset alone
  // Fraction 0.8 of the limits: 0.8 of it at 100 Hz.
  FeedforwardLimits part = limits;
  part.fraction = 0.8;
  EXPECT_NEAR(largest_sine_amplitude_m(static_gain(), part, 100.0, 0.0), 0.8 * 5.092958178940651e-07, 1e-20);
  // With the stage, divided by M(100 Hz).
  a = largest_sine_amplitude_m(with_stage(), limits, 100.0, 0.0);
  EXPECT_NEAR(a, 5.092958178940651e-07 / 0.9966853980599927, 1e-19);
}

TEST(Feasibility, HighestSineFrequencyByHandAndAtTheEdge) {
  const FeedforwardLimits limits;
  // 1 um, static gain: g S / (2 pi A) = 50.93 Hz.
  EXPECT_NEAR(highest_sine_frequency_hz(static_gain(), limits, 1e-6, 0.0), 50.92958178940652, 1e-11);
  EXPECT_EQ(highest_sine_frequency_hz(static_gain(), limits, 2e-6, 0.0), 0.0);  // 312.5 V at any frequency
  EXPECT_TRUE(std::isinf(highest_sine_frequency_hz(static_gain(), limits, 0.0, 0.0)));
  // With the stage: just below the edge fits, just above does not, and so does every lower frequency.
  auto edge_is_exact = [&](const LinearPlant& plant, const FeedforwardLimits& l, double amplitude, Limit beyond) {
    const double f = highest_sine_frequency_hz(plant, l, amplitude, 0.0);
    EXPECT_TRUE(fits(sine_need(plant, amplitude, f * (1 - 1e-9), 0.0), l)) << f;
    EXPECT_EQ(exceeded_limit(sine_need(plant, amplitude, f * (1 + 1e-9), 0.0), l), beyond) << f;
    for (double g = f / 1000; g < f; g += f / 1000) EXPECT_TRUE(fits(sine_need(plant, amplitude, g, 0.0), l)) << g;
    return f;
  };
  const double f_rate = edge_is_exact(with_stage(), limits, 1e-6, Limit::kSlew);
  EXPECT_NEAR(f_rate, 50.93, 0.2);  // M is within 1e-3 of 1 at 50 Hz
  // A range limit: 1.5 um (234.4 V at DC) with the slew limit out of the way meets the range where
  // M rises above 1, past sqrt(2k - c^2) (2.43 kHz).
  FeedforwardLimits fast = limits;
  fast.slew_V_per_s = 1e12;
  const double f_range = edge_is_exact(with_stage(), fast, 1.5e-6, Limit::kRange);
  EXPECT_GT(f_range, std::sqrt(2 * 1.17e8 - 2.03e3 * 2.03e3) / (2 * kPi));
  EXPECT_NEAR(stage_inverse_gain(with_stage(), f_range), 250.0 / 234.375, 1e-9);
  // The rate w A M(w) / g peaks near 0.58 f_n and dips at the resonance: a slew limit just below
  // the peak stops the first band there although the resonance fits again.
  const LinearPlant plant = with_stage();
  const double fn = std::sqrt(plant.stage->k) / (2 * kPi);
  FeedforwardLimits dip = limits;
  dip.slew_V_per_s = 0.98 * sine_need(plant, 1e-8, 0.58 * fn, 0.0).rate_V_per_s;
  const double f_dip = edge_is_exact(plant, dip, 1e-8, Limit::kSlew);
  EXPECT_LT(f_dip, 0.58 * fn);
  EXPECT_TRUE(fits(sine_need(plant, 1e-8, fn, 0.0), dip));
}

TEST(Feasibility, LargestTriangleAmplitude) {
  const FeedforwardLimits limits;
  // Sharp, static gain: v = 4 A f, so A = g S / (4 f) = 8 um at 10 Hz (the range allows 1.6 um),
  // 0.8 um at 100 Hz.
  EXPECT_NEAR(largest_triangle_amplitude_m(static_gain(), limits, 10.0, 0.0, 0.0), 1.6e-6, 1e-20);
  EXPECT_NEAR(largest_triangle_amplitude_m(static_gain(), limits, 100.0, 0.0, 0.0), 8e-7, 1e-20);
  EXPECT_EQ(largest_triangle_amplitude_m(with_stage(), limits, 10.0, 0.0, 0.0), 0.0);
  // With the stage and a corner: the amplitude found meets a limit exactly.
  for (const double corner : {1e-4, 1e-3}) {
    const double a = largest_triangle_amplitude_m(with_stage(), limits, 100.0, corner, 0.0);
    const VoltageNeed need = triangle_need(with_stage(), a, 100.0, corner, 0.0);
    EXPECT_TRUE(std::abs(need.rate_V_per_s - 5e4) < 1e-9 || std::abs(need.u_max_V - 250.0) < 1e-12) << corner;
    EXPECT_TRUE(fits(triangle_need(with_stage(), a * (1 - 1e-12), 100.0, corner, 0.0), limits)) << corner;
    EXPECT_FALSE(fits(triangle_need(with_stage(), a * (1 + 1e-9), 100.0, corner, 0.0), limits)) << corner;
  }
}

TEST(Feasibility, ShortestTriangleCorner) {
  const FeedforwardLimits limits;
  // No stage: the sharp corner, or nothing (a longer corner only steepens the straight parts).
  EXPECT_EQ(shortest_triangle_corner_s(static_gain(), limits, 1e-6, 10.0, 0.0), std::optional<double>(0.0));
  EXPECT_EQ(shortest_triangle_corner_s(static_gain(), limits, 1e-6, 100.0, 0.0), std::nullopt);  // 6.25e4 V/s
  // With the stage, 1 um at 10 Hz: v ~ 4e-5 m/s leaves a factor g S / v ~ 8 for the corner, so
  // pi^2 / (k tau^2) ~ 9: tau ~ pi / (3 w_n) = 97 us.
  const LinearPlant plant = with_stage();
  const auto tau = shortest_triangle_corner_s(plant, limits, 1e-6, 10.0, 0.0);
  ASSERT_TRUE(tau);
  EXPECT_NEAR(*tau, kPi / (3 * std::sqrt(plant.stage->k)), 0.05 * *tau);
  EXPECT_TRUE(fits(triangle_need(plant, 1e-6, 10.0, *tau, 0.0), limits));
  EXPECT_FALSE(fits(triangle_need(plant, 1e-6, 10.0, *tau * (1 - 1e-9), 0.0), limits));
  // Every shorter corner on a fine grid fails.
  for (double t = *tau / 2000; t < *tau * (1 - 1e-6); t += *tau / 2000) {
    EXPECT_FALSE(fits(triangle_need(plant, 1e-6, 10.0, t, 0.0), limits)) << t;
  }
  // Too fast for any corner: at 100 Hz the straight parts alone need at least 4 A f / g = 6.25e4 V/s.
  EXPECT_EQ(shortest_triangle_corner_s(plant, limits, 1e-6, 100.0, 0.0), std::nullopt);
}

TEST(Feasibility, HoldAndPoints) {
  TrajectorySpec hold;
  hold.offset_m = 1e-6;
  const VoltageNeed h = voltage_need(static_gain(), hold);
  EXPECT_NEAR(h.u_min_V, 156.25, 1e-12);
  EXPECT_NEAR(h.u_max_V, 156.25, 1e-12);
  EXPECT_EQ(h.rate_V_per_s, 0.0);
  TrajectorySpec pts;
  pts.shape = TrajectoryShape::kPoints;
  pts.n_points = 3;
  pts.points_t_s = {0.0, 0.01, 0.02};
  pts.points_y_m = {0.0, 6.4e-7, -6.4e-7};
  const VoltageNeed p = voltage_need(static_gain(), pts);
  EXPECT_NEAR(p.u_min_V, -100.0, 1e-12);
  EXPECT_NEAR(p.u_max_V, 100.0, 1e-12);
  EXPECT_NEAR(p.rate_V_per_s, 2e4, 1e-8);  // 1.28 um in 10 ms
  EXPECT_TRUE(std::isinf(voltage_need(with_stage(), pts).rate_V_per_s));
}

}  // namespace
}  // namespace hystloop
