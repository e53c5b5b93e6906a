#include "compensator/trajectory_message.hpp"

#include <algorithm>
#include <string>

#include "core/errors.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/trajectory_shape.hpp"

namespace hystloop {

TrajectorySpec trajectory_from_message(const trajectory_t& msg) {
  TrajectorySpec spec;
  const auto shape = trajectory_shape_from_wire(msg.shape);
  if (!shape) throw ParameterError("trajectory.shape", "unknown shape " + std::to_string(msg.shape));
  spec.shape = *shape;
  spec.amplitude_m = msg.amplitude_m;
  spec.offset_m = msg.offset_m;
  spec.frequency_hz = msg.frequency_Hz > 0.0 ? msg.frequency_Hz : 1.0;  // ignored for HOLD and POINTS
  spec.phase_rad = msg.phase_rad;
  spec.blend_s = msg.blend_s;
  // 0 on the wire asks the compensator for the shortest corner the limits allow; the spec carries
  // it as 0 (sharp) until the compensator has chosen.
  spec.corner_s = msg.shape == trajectory_t::TRIANGLE ? msg.corner_s : 0.0;
  switch (msg.if_infeasible) {
    case trajectory_t::REFUSE: spec.shape_if_infeasible = false; break;
    case trajectory_t::SHAPE: spec.shape_if_infeasible = true; break;
    default:
      throw ParameterError("trajectory.if_infeasible",
                           "must be REFUSE (0) or SHAPE (1) (got " + std::to_string(msg.if_infeasible) + ")");
  }
  if (!arrays_consistent(msg) || static_cast<std::size_t>(msg.n_points) > TrajectorySpec::kMaxPoints) {
    throw ParameterError("trajectory.n_points",
                         "must be 0.." + std::to_string(TrajectorySpec::kMaxPoints) + " and match the point arrays");
  }
  spec.n_points = static_cast<std::size_t>(msg.n_points);
  std::copy_n(msg.points_t_s.begin(), spec.n_points, spec.points_t_s.begin());
  std::copy_n(msg.points_y_m.begin(), spec.n_points, spec.points_y_m.begin());
  spec.validate();
  return spec;
}

double loop_time_of_utime(std::int64_t utime, std::int64_t sample_utime, std::int64_t sample_seq,
                          double dt_s) noexcept {
  return static_cast<double>(sample_seq) * dt_s + static_cast<double>(utime - sample_utime) * 1e-6;
}

}  // namespace hystloop
