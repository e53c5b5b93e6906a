#pragma once
// trajectory_t (the wire) -> TrajectorySpec (the control law's reference). The message has
// passed the contract check already (common/lcm/message_checks.hpp); what is left is the
// mapping of its start time to loop time, which needs the latest sample's (utime, seq).

#include <cstdint>

#include "hystloop/trajectory_t.hpp"
#include "loop/trajectory.hpp"

namespace hystloop {

// Shape, amplitude, offset, frequency, phase, blend, points, the triangle's corner_s (0 for the
// other shapes; 0 for a triangle means "the shortest the limits allow": the caller chooses it) and
// if_infeasible as spec.shape_if_infeasible; start_s and hold_m are left to the caller. Throws
// ParameterError naming the field when the spec is unusable.
TrajectorySpec trajectory_from_message(const trajectory_t& msg);

// Loop time [s] of wall time `utime` [us], given that sample `sample_seq` was taken at
// `sample_utime` [us] and ticks are dt_s apart.
double loop_time_of_utime(std::int64_t utime, std::int64_t sample_utime, std::int64_t sample_seq, double dt_s) noexcept;

}  // namespace hystloop
