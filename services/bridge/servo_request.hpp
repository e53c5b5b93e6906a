#pragma once
// HX_CONTROL SET_GAINS: the servo's gains a request asks for. kp, ki, kd and the notch come from
// the message where it gives them (NaN: the one in force stays); the nominal gain, the actuator's range, the derivative
// filter and the tick rate stay as in force (they are the rig's, not the request's).

#include "hystloop/control_t.hpp"
#include "loop/feedback.hpp"

namespace hystloop {

// The gains to hand to the real-time thread. Throws ParameterError naming the field ("servo.kp:
// must be <= 2 (got 1e+300): ...") for a request outside FeedbackGains::check_bounds at the
// bridge's tick rate; the caller then keeps the gains in force.
FeedbackGains requested_gains(const FeedbackGains& in_force, const control_t& msg);

}  // namespace hystloop
