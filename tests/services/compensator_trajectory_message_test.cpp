// trajectory_t -> TrajectorySpec: the triangle's corner and what to do with an infeasible
// trajectory, as the compensator receives them.
#include "compensator/trajectory_message.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"

namespace hystloop {
namespace {

trajectory_t triangle_message(double corner_s, std::int8_t if_infeasible) {
  trajectory_t t{};
  t.version = 1;
  t.shape = trajectory_t::TRIANGLE;
  t.amplitude_m = 1e-6;
  t.frequency_Hz = 10.0;
  t.corner_s = corner_s;
  t.if_infeasible = if_infeasible;
  return t;
}

std::string field_of(const trajectory_t& t) {
  try {
    trajectory_from_message(t);
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "<no error>";
}

TEST(TrajectoryMessage, CornerAndPolicyReachTheSpec) {
  TrajectorySpec s = trajectory_from_message(triangle_message(0.004, trajectory_t::SHAPE));
  EXPECT_EQ(s.shape, TrajectoryShape::kTriangle);
  EXPECT_EQ(s.corner_s, 0.004);
  EXPECT_TRUE(s.shape_if_infeasible);
  s = trajectory_from_message(triangle_message(0.0, trajectory_t::REFUSE));
  EXPECT_EQ(s.corner_s, 0.0);  // the compensator's to choose
  EXPECT_FALSE(s.shape_if_infeasible);
  // The corner rounds the triangle it evaluates: the same peak, approached smoothly (above the sharp
  // one just before it).
  const TrajectorySpec rounded = trajectory_from_message(triangle_message(0.01, trajectory_t::REFUSE));
  EXPECT_NEAR(evaluate_shape(rounded, 0.025), 1e-6, 1e-21);
  EXPECT_GT(evaluate_shape(rounded, 0.024), evaluate_shape(s, 0.024) + 1e-8);
  // Other shapes ignore the corner.
  trajectory_t sine = triangle_message(0.3, trajectory_t::REFUSE);
  sine.shape = trajectory_t::SINE;
  EXPECT_EQ(trajectory_from_message(sine).corner_s, 0.0);
}

TEST(TrajectoryMessage, RefusesACornerOrPolicyItCannotUse) {
  EXPECT_EQ(field_of(triangle_message(0.05, trajectory_t::REFUSE)), "trajectory.corner_s");  // half the period
  EXPECT_EQ(field_of(triangle_message(-1e-3, trajectory_t::REFUSE)), "trajectory.corner_s");
  EXPECT_EQ(field_of(triangle_message(std::nan(""), trajectory_t::REFUSE)), "trajectory.corner_s");
  EXPECT_EQ(field_of(triangle_message(0.0, 2)), "trajectory.if_infeasible");
  EXPECT_EQ(field_of(triangle_message(0.0, -1)), "trajectory.if_infeasible");
}

}  // namespace
}  // namespace hystloop
