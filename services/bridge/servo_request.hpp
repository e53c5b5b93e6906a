#pragma once
// HX_CONTROL SET_GAINS: the servo's gains a request asks for. kp, ki, kd and the notch come from
// the message where it gives them (NaN: the one in force stays); the nominal gain, the actuator's range, the derivative
// filter and the tick rate stay as in force (they are the rig's, not the request's).

#include <array>

#include "hystloop/control_t.hpp"
#include "loop/feedback.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

// The gains to hand to the real-time thread. Throws ParameterError naming the field ("servo.kp:
// must be <= 2 (got 1e+300): ...") for a request outside FeedbackGains::check_bounds at the
// bridge's tick rate; the caller then keeps the gains in force.
FeedbackGains requested_gains(const FeedbackGains& in_force, const control_t& msg);

// A stage's request: the axes it sets and their new gains (the others' as in force).
struct AxisGainsChange {
  std::array<bool, kMaxAxes> set{};
  std::array<FeedbackGains, kMaxAxes> gains{};
};

// SET_GAINS on a stage of `axes` axes whose servos have `in_force`: msg.axis's servo, or every
// axis's (control_t::EVERY_AXIS, each keeping its own value of a field sent as NaN). All or none:
// throws ParameterError naming "control.axis" for an axis the stage does not have, or the field
// of the first axis the request does not fit ("servo.y.kp" on a stage of several axes).
AxisGainsChange requested_axis_gains(const std::array<FeedbackGains, kMaxAxes>& in_force, int axes,
                                     const control_t& msg);

}  // namespace hystloop
