#include "loop/trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

TEST(Trajectory, ShapeNamesAreOneTableBothWays) {
  for (std::size_t i = 0; i < kTrajectoryShapeNames.size(); ++i) {
    const auto shape = static_cast<TrajectoryShape>(i);
    EXPECT_EQ(trajectory_shape_named(to_string(shape)), shape) << i;
  }
  EXPECT_EQ(trajectory_shape_named("triangle"), TrajectoryShape::kTriangle);
  EXPECT_EQ(to_string(TrajectoryShape::kCosine), "cosine");
  EXPECT_FALSE(trajectory_shape_named("Triangle").has_value());  // names are exact, as in the config
  EXPECT_FALSE(trajectory_shape_named("").has_value());
  EXPECT_EQ(to_string(static_cast<TrajectoryShape>(9)), "unknown");
  EXPECT_EQ(trajectory_shape_choices(), "hold, sine, cosine, triangle or points");
}

TEST(Trajectory, MemPaperReferenceIsEq24) {
  const TrajectorySpec s = mem_paper_reference(0.0);
  for (double t : {0.0, 0.1, 0.25, 0.5, 0.77, 3.0}) {
    EXPECT_NEAR(evaluate(s, t), -1.6e-6 * std::cos(2 * std::numbers::pi * t), 1e-18) << t;
  }
}

TEST(Trajectory, ApproachIsMonotoneFromHoldToTheShapeWithoutAStep) {
  const TrajectorySpec s = mem_paper_reference(1.0, 0.5, 0.3e-6);
  EXPECT_EQ(evaluate(s, 0.2), 0.3e-6);  // before the approach: hold
  // Half way the quintic is at 1/2 of the way plus c/64, c = a_e L^2 / delta: it arrives with the
  // cosine's curvature 1.6e-6 (2 pi)^2 (trajectory.cpp, evaluate).
  const double c = 1.6e-6 * 4.0 * std::numbers::pi * std::numbers::pi * 0.25 / (-1.6e-6 - 0.3e-6);
  EXPECT_NEAR(evaluate(s, 0.75), 0.3e-6 + (-1.9e-6) * (0.5 + c / 64.0), 1e-14);
  EXPECT_NEAR(evaluate(s, 1.0), -1.6e-6, 1e-18);  // the shape's first value at start_s
  EXPECT_NEAR(evaluate(s, 1.6), -1.6e-6 * std::cos(2 * std::numbers::pi * 0.6), 1e-18);
  double prev = evaluate(s, 0.4);
  for (double t = 0.5; t < 1.0; t += 1e-4) {
    const double y = evaluate(s, t);
    EXPECT_LE(y, prev) << t;  // one branch down to the start: no reversal in the approach
    EXPECT_LT(prev - y, 2e-9) << t;
    prev = y;
  }
}

TEST(Trajectory, TriangleAndPoints) {
  TrajectorySpec tri;
  tri.shape = TrajectoryShape::kTriangle;
  tri.amplitude_m = 1e-6;
  tri.frequency_hz = 2.0;
  EXPECT_NEAR(evaluate(tri, 0.0), 0.0, 1e-18);
  EXPECT_NEAR(evaluate(tri, 0.125), 1e-6, 1e-15);
  EXPECT_NEAR(evaluate(tri, 0.375), -1e-6, 1e-15);
  TrajectorySpec pts;
  pts.shape = TrajectoryShape::kPoints;
  pts.n_points = 3;
  pts.points_t_s = {0.0, 1.0, 3.0};
  pts.points_y_m = {0.0, 2e-6, -2e-6};
  pts.validate();
  EXPECT_NEAR(evaluate(pts, 0.5), 1e-6, 1e-18);
  EXPECT_NEAR(evaluate(pts, 2.0), 0.0, 1e-18);
  EXPECT_NEAR(evaluate(pts, 10.0), -2e-6, 1e-18);
}

TEST(Trajectory, ValidationNamesTheField) {
  TrajectorySpec s = mem_paper_reference(0.0);
  s.frequency_hz = -1;
  try {
    s.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "trajectory.frequency_hz");
  }
  TrajectorySpec p;
  p.shape = TrajectoryShape::kPoints;
  p.n_points = 2;
  p.points_t_s = {1.0, 1.0};
  EXPECT_THROW(p.validate(), ParameterError);
}

constexpr double kPi = std::numbers::pi;

TrajectorySpec triangle(double amplitude_m, double frequency_hz, double corner_s, double offset_m = 0.0) {
  TrajectorySpec s;
  s.shape = TrajectoryShape::kTriangle;
  s.amplitude_m = amplitude_m;
  s.frequency_hz = frequency_hz;
  s.corner_s = corner_s;
  s.offset_m = offset_m;
  s.validate();
  return s;
}

// The slope of the straight parts from 2A = v (T/2 - tau) + 2 v tau / pi.
double slope_of(double a, double f, double tau) { return 2.0 * a / (0.5 / f - tau + 2.0 * tau / kPi); }

TEST(RoundedTriangle, ZeroCornerIsTheSharpTriangleBitForBit) {
  TrajectorySpec s = triangle(1.3e-6, 7.0, 0.0, 2e-7);
  s.phase_rad = 0.4;
  for (int i = -50; i < 3000; ++i) {
    const double tau = 1.234e-4 * i;
    const double phase = 2.0 * kPi * s.frequency_hz * tau + s.phase_rad;
    const double x = phase / (2.0 * kPi) - std::floor(phase / (2.0 * kPi));
    const double tri = x < 0.25 ? 4.0 * x : (x < 0.75 ? 2.0 - 4.0 * x : 4.0 * x - 4.0);
    EXPECT_EQ(evaluate_shape(s, tau), s.offset_m + s.amplitude_m * tri) << tau;
  }
}

TEST(RoundedTriangle, PeaksPeriodAndPhaseAreTheSharpTriangles) {
  const double a = 2e-6, f = 5.0, corner = 0.03, offset = -3e-7;  // T = 0.2 s: corners 30 % of a half period
  const TrajectorySpec s = triangle(a, f, corner, offset);
  EXPECT_NEAR(evaluate_shape(s, 0.0), offset, 1e-21);
  EXPECT_NEAR(evaluate_shape(s, 0.05), offset + a, 1e-21);  // a quarter period: the top
  EXPECT_NEAR(evaluate_shape(s, 0.10), offset, 1e-20);
  EXPECT_NEAR(evaluate_shape(s, 0.15), offset - a, 1e-21);
  double top = -1.0, bottom = 1.0;
  for (double t = 0.0; t < 0.2; t += 1e-5) {
    const double y = evaluate_shape(s, t);
    top = std::max(top, y);
    bottom = std::min(bottom, y);
    EXPECT_NEAR(evaluate_shape(s, t + 0.2), y, 1e-19) << t;
    EXPECT_NEAR(evaluate_shape(s, t + 7 * 0.2), y, 1e-18) << t;
  }
  EXPECT_LE(top, offset + a + 1e-21);  // the grid misses the top by up to 5 us, a few 1e-14 m below it
  EXPECT_GT(top, offset + a - 1e-13);
  EXPECT_GE(bottom, offset - a - 1e-21);
  EXPECT_LT(bottom, offset - a + 1e-13);
  // The phase convention of sine: a quarter period of phase moves the top to t = 0.
  TrajectorySpec shifted = s;
  shifted.phase_rad = kPi / 2;
  EXPECT_NEAR(evaluate_shape(shifted, 0.0), offset + a, 1e-20);
  // A negative amplitude flips it.
  TrajectorySpec flipped = s;
  flipped.amplitude_m = -a;
  EXPECT_NEAR(evaluate_shape(flipped, 0.0123) - offset, -(evaluate_shape(s, 0.0123) - offset), 1e-21);
}

// Position, velocity and acceleration are continuous where the straight parts meet the corners;
// on the straight parts the velocity is v, at a corner's middle the acceleration is -v pi / tau,
// and the jerk at its ends +-v pi^2 / tau^2.
TEST(RoundedTriangle, DerivativesAreContinuousAndMatchTheClosedForms) {
  const double a = 1e-6, f = 10.0, corner = 0.004;
  const TrajectorySpec s = triangle(a, f, corner);
  const double v = slope_of(a, f, corner);
  EXPECT_NEAR(triangle_slope_m_per_s(s), v, 1e-15 * v);
  const double h = 1e-7;
  auto y = [&](double t) { return evaluate_shape(s, t); };
  auto velocity = [&](double t) { return (y(t + h) - y(t - h)) / (2 * h); };
  auto acceleration = [&](double t) { return (y(t + h) - 2 * y(t) + y(t - h)) / (h * h); };
  const double quarter = 0.025, half_corner = corner / 2;
  for (const double join : {quarter - half_corner, quarter + half_corner, 3 * quarter - half_corner,
                            3 * quarter + half_corner, 0.1 + quarter - half_corner}) {
    EXPECT_NEAR(y(join + 1e-12), y(join - 1e-12), 3e-12 * v + 1e-21) << join;
    EXPECT_NEAR(std::abs(velocity(join)), v, 1e-6 * v) << join;
    EXPECT_NEAR(std::abs(velocity(join + 5e-7)), v, 1e-4 * v) << join;             // just inside the corner
    EXPECT_NEAR(std::abs(velocity(join - 5e-7)), v, 1e-4 * v) << join;             // just outside
    EXPECT_NEAR(acceleration(join + 1e-6), 0.0, 2e-3 * v * kPi / corner) << join;  // (v pi / tau) sin(pi 1e-6 / tau)
    EXPECT_NEAR(acceleration(join - 1e-6), 0.0, 2e-3 * v * kPi / corner) << join;
  }
  EXPECT_NEAR(acceleration(quarter), -v * kPi / corner, 1e-4 * v * kPi / corner);
  EXPECT_NEAR(acceleration(3 * quarter), v * kPi / corner, 1e-4 * v * kPi / corner);
  // Jerk by a third difference just inside the corner's start: v pi^2 / tau^2 in magnitude.
  const double t0 = quarter - half_corner + 1e-5, d = 2e-6;
  const double jerk = (y(t0 + 2 * d) - 3 * y(t0 + d) + 3 * y(t0) - y(t0 - d)) / (d * d * d);
  EXPECT_NEAR(jerk, -v * kPi * kPi / (corner * corner), 0.02 * v * kPi * kPi / (corner * corner));
  const ShapePeaks p = peak_derivatives(s);
  EXPECT_NEAR(p.velocity_m_per_s, v, 1e-15 * v);
  EXPECT_NEAR(p.acceleration_m_per_s2, v * kPi / corner, 1e-12 * v * kPi / corner);
  EXPECT_NEAR(p.jerk_m_per_s3, v * kPi * kPi / (corner * corner), 1e-12 * p.jerk_m_per_s3);
  // Over the whole period nothing moves faster than v.
  for (double t = 0.0; t < 0.1; t += 1e-5) EXPECT_LE(std::abs(velocity(t)), v * (1 + 1e-6)) << t;
}

TEST(RoundedTriangle, TheStraightPartsRiseAtTheClosedFormsSlope) {
  for (const double corner : {1e-5, 0.01, 0.049}) {  // up to nearly half the period (0.05 s at 10 Hz)
    const double a = 1.5e-6, f = 10.0;
    const TrajectorySpec s = triangle(a, f, corner);
    const double v = slope_of(a, f, corner);
    const double t0 = -0.025 + corner / 2, t1 = 0.025 - corner / 2;  // the rising part, centred on t = 0
    EXPECT_NEAR((evaluate_shape(s, t1) - evaluate_shape(s, t0)) / (t1 - t0), v, 1e-9 * v) << corner;
    EXPECT_NEAR(evaluate_shape(s, 0.01 * (t1 - t0) + t0), v * (0.01 * (t1 - t0) + t0), 1e-9 * a) << corner;
    // The corner gives up v tau / pi of the peak's height: what the straight part does not reach.
    EXPECT_NEAR(evaluate_shape(s, t1), a - v * corner / kPi, 1e-12 * a) << corner;
  }
  // The limits: sharp (4 A f) and all corner (the sine's peak velocity 2 pi A f).
  EXPECT_NEAR(slope_of(1.0, 1.0, 0.0), 4.0, 1e-15);
  EXPECT_NEAR(slope_of(1.0, 1.0, 0.5), 2.0 * kPi, 1e-15);
}

TEST(RoundedTriangle, EvaluationAllocatesNothing) {
  const TrajectorySpec s = triangle(1e-6, 10.0, 0.002);
  testing::AllocationCounter counter;
  double sum = 0.0;
  for (int k = 0; k < 10000; ++k) sum += evaluate(s, 1e-4 * k);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

TEST(RoundedTriangle, CornerIsValidated) {
  auto field_of = [](double corner) -> std::string {
    TrajectorySpec s;
    s.shape = TrajectoryShape::kTriangle;
    s.frequency_hz = 10.0;
    s.corner_s = corner;
    try {
      s.validate();
    } catch (const ParameterError& e) {
      return e.field();
    }
    return "";
  };
  EXPECT_EQ(field_of(0.0), "");
  EXPECT_EQ(field_of(0.0499), "");
  EXPECT_EQ(field_of(0.05), "trajectory.corner_s");  // half the period
  EXPECT_EQ(field_of(-1e-3), "trajectory.corner_s");
  EXPECT_EQ(field_of(std::nan("")), "trajectory.corner_s");
}

TEST(Trajectory, PeriodicShapesAndTheirPeriodInTicks) {
  TrajectorySpec s = mem_paper_reference(0.0);
  EXPECT_TRUE(periodic(s));
  s.frequency_hz = 10.0;
  EXPECT_EQ(period_ticks(s, 1e-4), std::optional<std::int64_t>(1000));
  s.frequency_hz = 30.0;  // 333.33 ticks
  EXPECT_EQ(period_ticks(s, 1e-4), std::nullopt);
  s.frequency_hz = 2.5;
  EXPECT_EQ(period_ticks(s, 1e-4), std::optional<std::int64_t>(4000));
  s.frequency_hz = 1.0 / (1.0 + 2e-9);  // 1000.000002 ticks: 2e-9 relative off a whole number
  EXPECT_EQ(period_ticks(s, 1e-3), std::nullopt);
  s.frequency_hz = 1.0 / (1.0 + 5e-10);  // within 1e-9
  EXPECT_EQ(period_ticks(s, 1e-3), std::optional<std::int64_t>(1000));
  s.frequency_hz = 20000.0;  // half a tick
  EXPECT_EQ(period_ticks(s, 1e-4), std::nullopt);
  s.frequency_hz = 10.0;
  EXPECT_EQ(period_ticks(s, 0.0), std::nullopt);
  s.shape = TrajectoryShape::kTriangle;
  EXPECT_TRUE(periodic(s));
  EXPECT_EQ(period_ticks(s, 2e-4), std::optional<std::int64_t>(500));
  s.shape = TrajectoryShape::kSine;
  EXPECT_TRUE(periodic(s));
  for (const TrajectoryShape other : {TrajectoryShape::kHold, TrajectoryShape::kPoints}) {
    s.shape = other;
    EXPECT_FALSE(periodic(s));
    EXPECT_EQ(period_ticks(s, 1e-4), std::nullopt);
  }
}

TEST(Trajectory, PeakDerivativesOfEachShape) {
  TrajectorySpec sine = mem_paper_reference(0.0);  // 1.6 um at 1 Hz
  const double w = 2 * kPi;
  ShapePeaks p = peak_derivatives(sine);
  EXPECT_NEAR(p.velocity_m_per_s, w * 1.6e-6, 1e-20);
  EXPECT_NEAR(p.acceleration_m_per_s2, w * w * 1.6e-6, 1e-19);
  EXPECT_NEAR(p.jerk_m_per_s3, w * w * w * 1.6e-6, 1e-18);
  const TrajectorySpec sharp = triangle(1e-6, 10.0, 0.0);
  p = peak_derivatives(sharp);
  EXPECT_NEAR(p.velocity_m_per_s, 4e-5, 1e-20);  // 4 A f
  EXPECT_TRUE(std::isinf(p.acceleration_m_per_s2));
  EXPECT_EQ(peak_derivatives(TrajectorySpec{}).velocity_m_per_s, 0.0);
  TrajectorySpec pts;
  pts.shape = TrajectoryShape::kPoints;
  pts.n_points = 3;
  pts.points_t_s = {0.0, 1.0, 1.5};
  pts.points_y_m = {0.0, 1e-6, -1e-6};
  p = peak_derivatives(pts);
  EXPECT_NEAR(p.velocity_m_per_s, 4e-6, 1e-21);
  EXPECT_TRUE(std::isinf(p.acceleration_m_per_s2));
  EXPECT_EQ(triangle_slope_m_per_s(sine), 0.0);
}

}  // namespace
}  // namespace hystloop
