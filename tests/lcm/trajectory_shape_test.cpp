// trajectory_t's shape numbers <-> TrajectoryShape: every number the wire defines maps to its
// shape, anything else is refused rather than cast into the enum.
#include "lcm/trajectory_shape.hpp"

#include <gtest/gtest.h>

namespace hystloop {
namespace {

TEST(TrajectoryShapeWire, EveryWireShapeRoundTripsAndOthersAreRefused) {
  for (std::int8_t w :
       {trajectory_t::HOLD, trajectory_t::SINE, trajectory_t::COSINE, trajectory_t::TRIANGLE, trajectory_t::POINTS}) {
    const auto shape = trajectory_shape_from_wire(w);
    ASSERT_TRUE(shape.has_value()) << int{w};
    EXPECT_EQ(to_wire(*shape), w);
  }
  EXPECT_EQ(trajectory_shape_from_wire(trajectory_t::TRIANGLE), TrajectoryShape::kTriangle);
  for (std::int8_t w : {std::int8_t{-1}, std::int8_t{5}, std::int8_t{127}, std::int8_t{-128}}) {
    EXPECT_FALSE(trajectory_shape_from_wire(w).has_value()) << int{w};
  }
}

}  // namespace
}  // namespace hystloop
