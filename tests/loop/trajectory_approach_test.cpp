// The approach into a periodic shape: it ends at the shape's first peak or trough (entered from
// the side the shape bends away from), at rest and with the shape's curvature, monotone, so that
// neither the stage's inverse (which differentiates twice) nor a hysteresis model's memory (which
// starts a branch at every reversal) sees a kink or an extra reversal.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "loop/trajectory.hpp"

namespace hystloop {
namespace {

TrajectorySpec periodic_spec(TrajectoryShape shape, double f, double hold, double corner = 0.0) {
  TrajectorySpec s;
  s.shape = shape;
  s.amplitude_m = 0.5e-6;
  s.frequency_hz = f;
  s.start_s = 1.0;
  s.blend_s = 0.2;
  s.hold_m = hold;
  s.corner_s = corner;
  return s;
}

// Position, velocity and acceleration by central differences at step h.
struct Motion {
  double y, v, a;
};
Motion motion(const TrajectorySpec& s, double t, double h) {
  const double y0 = evaluate(s, t - h), y1 = evaluate(s, t), y2 = evaluate(s, t + h);
  return {y1, (y2 - y0) / (2 * h), (y2 - 2 * y1 + y0) / (h * h)};
}

TEST(TrajectoryApproach, ASineIsEnteredAtItsFirstPeakAtRestWithItsCurvature) {
  for (const double f : {10.0, 50.0, 200.0}) {
    const TrajectorySpec s = periodic_spec(TrajectoryShape::kSine, f, 0.0);
    const double enter = first_extreme_s(s);
    EXPECT_NEAR(enter, 0.25 / f, 1e-15) << f;  // from 0 up to the first peak
    const double h = 1e-6 / f;
    const Motion before = motion(s, s.start_s + enter - 4 * h, h);
    const Motion after = motion(s, s.start_s + enter + 4 * h, h);
    const double w = 2 * std::numbers::pi * f;
    EXPECT_NEAR(before.y, after.y, 1e-12 * 0.5e-6 + 0.5e-6 * w * w * 32 * h * h) << f;
    EXPECT_NEAR(before.a, -0.5e-6 * w * w, 1e-3 * 0.5e-6 * w * w) << f;  // the sine's own curvature
    EXPECT_NEAR(after.a, -0.5e-6 * w * w, 1e-3 * 0.5e-6 * w * w) << f;
  }
}

TEST(TrajectoryApproach, IsMonotoneAndNeverFasterThanTheShape) {
  for (const TrajectoryShape shape : {TrajectoryShape::kSine, TrajectoryShape::kTriangle, TrajectoryShape::kCosine}) {
    for (const double hold : {-2e-6, 0.0, 0.3e-6, 3e-6}) {
      for (const double f : {10.0, 100.0}) {
        const TrajectorySpec s = periodic_spec(shape, f, hold, shape == TrajectoryShape::kTriangle ? 0.05 / f : 0.0);
        const double end = s.start_s + first_extreme_s(s);
        const double sign = evaluate(s, end) >= hold ? 1.0 : -1.0;
        double prev = evaluate(s, s.start_s - s.blend_s - 0.01);
        EXPECT_EQ(prev, hold);
        const double shape_speed = 2 * std::numbers::pi * f * 0.5e-6 * 1.6;  // a triangle's slope is below this
        const double dt = 1e-5;
        for (double t = s.start_s - s.blend_s; t <= end; t += dt) {
          const double y = evaluate(s, t);
          EXPECT_GE(sign * (y - prev), -1e-21) << "shape " << static_cast<int>(shape) << " hold " << hold << " t " << t;
          EXPECT_LE(std::abs(y - prev) / dt, std::max(shape_speed, 1.2 * std::abs(hold - evaluate(s, end)) / 0.2 * 2))
              << "shape " << static_cast<int>(shape) << " hold " << hold << " f " << f;
          prev = y;
        }
      }
    }
  }
}

TEST(TrajectoryApproach, AShapeAboveTheHoldIsEnteredAtAPeakAndBelowAtATrough) {
  // Held above a sine's peaks: entered at its first trough instead (from above), half a period on.
  const TrajectorySpec high = periodic_spec(TrajectoryShape::kSine, 50.0, 3e-6);
  EXPECT_NEAR(first_extreme_s(high), 0.75 / 50.0, 1e-15);
  const TrajectorySpec low = periodic_spec(TrajectoryShape::kSine, 50.0, -3e-6);
  EXPECT_NEAR(first_extreme_s(low), 0.25 / 50.0, 1e-15);
  // The MEM paper's cosine starts at its trough: entered there, at start_s, as before.
  EXPECT_EQ(first_extreme_s(mem_paper_reference(1.0, 0.5, 0.0)), 0.0);
}

}  // namespace
}  // namespace hystloop
