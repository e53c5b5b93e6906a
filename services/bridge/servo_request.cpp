#include "bridge/servo_request.hpp"

namespace hystloop {

FeedbackGains requested_gains(const FeedbackGains& in_force, const control_t& msg) {
  FeedbackGains g = in_force;
  g.kp = msg.kp;
  g.ki = msg.ki;
  g.kd = msg.kd;
  // A sender that knows no notch sends 0 and 0: no notch, which validates as such.
  g.notch_hz = msg.notch_hz;
  g.notch_q = msg.notch_q;
  g.check_bounds();  // finite, >= 0, and within the plausibility bounds at this tick rate
  return g;
}

}  // namespace hystloop
