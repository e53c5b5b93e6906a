#pragma once
// trajectory_t's shape field <-> TrajectoryShape. The wire's constants are the enum's numbers;
// this is the one place that says so, and the compiler checks it.

#include <cstdint>
#include <optional>

#include "hystloop/trajectory_t.hpp"
#include "loop/trajectory.hpp"

namespace hystloop {

static_assert(trajectory_t::HOLD == static_cast<std::int8_t>(TrajectoryShape::kHold));
static_assert(trajectory_t::SINE == static_cast<std::int8_t>(TrajectoryShape::kSine));
static_assert(trajectory_t::COSINE == static_cast<std::int8_t>(TrajectoryShape::kCosine));
static_assert(trajectory_t::TRIANGLE == static_cast<std::int8_t>(TrajectoryShape::kTriangle));
static_assert(trajectory_t::POINTS == static_cast<std::int8_t>(TrajectoryShape::kPoints));
static_assert(kTrajectoryShapeNames.size() == static_cast<std::size_t>(TrajectoryShape::kPoints) + 1);

// Empty for a number that names no shape (a newer sender, or a corrupted field).
inline std::optional<TrajectoryShape> trajectory_shape_from_wire(std::int8_t shape) noexcept {
  if (shape < trajectory_t::HOLD || shape > trajectory_t::POINTS) return std::nullopt;
  return static_cast<TrajectoryShape>(shape);
}

inline std::int8_t to_wire(TrajectoryShape shape) noexcept { return static_cast<std::int8_t>(shape); }

}  // namespace hystloop
