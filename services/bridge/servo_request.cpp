#include "bridge/servo_request.hpp"

#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

FeedbackGains requested_gains(const FeedbackGains& in_force, const control_t& msg) {
  FeedbackGains g = in_force;
  // NaN: the sender leaves that one as it is.
  const auto take = [](double& field, double requested) {
    if (!std::isnan(requested)) field = requested;
  };
  take(g.kp, msg.kp);
  take(g.ki, msg.ki);
  take(g.kd, msg.kd);
  // A sender that knows no notch sends 0 and 0: no notch, which validates as such.
  take(g.notch_hz, msg.notch_hz);
  take(g.notch_q, msg.notch_q);
  take(g.notch2_hz, msg.notch2_hz);
  take(g.notch2_q, msg.notch2_q);
  g.check_bounds();  // finite, >= 0, and within the plausibility bounds at this tick rate
  return g;
}

AxisGainsChange requested_axis_gains(const std::array<FeedbackGains, kMaxAxes>& in_force, int axes,
                                     const control_t& msg) {
  const bool every = msg.axis == control_t::EVERY_AXIS;
  if (!every && (msg.axis < 0 || msg.axis >= axes)) {
    throw ParameterError("control.axis", "the stage has " + std::to_string(axes) + (axes == 1 ? " axis" : " axes") +
                                             " (got axis " + std::to_string(msg.axis) + ")");
  }
  AxisGainsChange change;
  change.gains = in_force;
  for (int a = every ? 0 : msg.axis; a <= (every ? axes - 1 : msg.axis); ++a) {
    const auto at = static_cast<std::size_t>(a);
    try {
      change.gains[at] = requested_gains(in_force[at], msg);
    } catch (const ParameterError& e) {
      if (axes == 1) throw;
      throw ParameterError(axis_field(e.field(), a), e.reason());
    }
    change.set[at] = true;
  }
  return change;
}

}  // namespace hystloop
