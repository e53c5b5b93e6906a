#include "loop/trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {
namespace {

TEST(Trajectory, MemPaperReferenceIsEq24) {
  const TrajectorySpec s = mem_paper_reference(0.0);
  for (double t : {0.0, 0.1, 0.25, 0.5, 0.77, 3.0}) {
    EXPECT_NEAR(evaluate(s, t), -1.6e-6 * std::cos(2 * std::numbers::pi * t), 1e-18) << t;
  }
}

TEST(Trajectory, ApproachIsMonotoneFromHoldToTheShapeWithoutAStep) {
  const TrajectorySpec s = mem_paper_reference(1.0, 0.5, 0.3e-6);
  EXPECT_EQ(evaluate(s, 0.2), 0.3e-6);                           // before the approach: hold
  EXPECT_NEAR(evaluate(s, 0.75), (0.3e-6 - 1.6e-6) / 2, 1e-18);  // half way
  EXPECT_NEAR(evaluate(s, 1.0), -1.6e-6, 1e-18);                 // the shape's first value at start_s
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

}  // namespace
}  // namespace hystloop
