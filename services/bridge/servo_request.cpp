#include "bridge/servo_request.hpp"

#include <cmath>

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
  g.check_bounds();  // finite, >= 0, and within the plausibility bounds at this tick rate
  return g;
}

}  // namespace hystloop
