#pragma once
// PID on the tracking error, added to the feedforward voltage. Gains are normalised by
// the stage's nominal gain so that they read in plain units whatever the stage:
//   u_fb [V] = (kp * e + ki * integral(e) + kd * de/dt) / nominal_gain_m_per_V,   e = y_ref - y [m]
// kp [-], ki [1/s], kd [s]. With the feedforward linearising the stage to ~unit gain,
// ki is roughly the loop's crossover in rad/s. Anti-windup: the integrator stops
// growing in the direction in which the total command already saturates at u_min_V or
// u_max_V (conditional integration), so a clamp never winds it up.

#include "core/errors.hpp"

namespace hystloop {

struct FeedbackGains {
  double kp = 0.0;                       // [-]
  double ki = 0.0;                       // [1/s]
  double kd = 0.0;                       // [s]
  double nominal_gain_m_per_V = 6.4e-9;  // stage's mean slope dy/du (Banning stage: ~1.6 um / 250 V)
  double u_min_V = -250.0;               // the range of u_ff + u_fb the actuator allows (for anti-windup)
  double u_max_V = 250.0;
  double d_filter_hz = 1000.0;  // first-order low-pass on the derivative

  void validate() const;
  bool enabled() const noexcept { return kp != 0.0 || ki != 0.0 || kd != 0.0; }
};

class FeedbackController {
 public:
  explicit FeedbackController(const FeedbackGains& gains = {});

  // Voltage correction for error e [m] after dt [s], given the feedforward part u_ff [V]
  // (needed for anti-windup). Allocation- and throw-free.
  double update(double error_m, double u_ff_V, double dt_s) noexcept;

  // New gains; the integral is rescaled so that the output does not jump (bumpless).
  void set_gains(const FeedbackGains& gains);
  const FeedbackGains& gains() const noexcept { return gains_; }
  void reset() noexcept;
  double integral_m_s() const noexcept { return integral_; }

 private:
  FeedbackGains gains_;
  double integral_ = 0.0;  // [m s]
  double prev_error_ = 0.0;
  double d_state_ = 0.0;  // filtered derivative [m/s]
  bool has_prev_ = false;
};

}  // namespace hystloop
