#include "loop/feedback.hpp"

#include <cmath>
#include <numbers>

namespace hystloop {

void FeedbackGains::validate() const {
  require_non_negative("feedback.kp", kp);
  require_non_negative("feedback.ki", ki);
  require_non_negative("feedback.kd", kd);
  require_positive("feedback.nominal_gain_m_per_V", nominal_gain_m_per_V);
  require_finite("feedback.u_min_V", u_min_V);
  require_finite("feedback.u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("feedback.u_max_V", "must be greater than feedback.u_min_V");
  require_positive("feedback.d_filter_hz", d_filter_hz);
}

FeedbackController::FeedbackController(const FeedbackGains& gains) : gains_(gains) { gains_.validate(); }

void FeedbackController::set_gains(const FeedbackGains& gains) {
  gains.validate();
  // Keep ki * integral constant so the integral part of the output does not jump.
  if (gains.ki > 0.0 && gains_.ki > 0.0) {
    integral_ *= gains_.ki / gains.ki;
  } else if (gains.ki == 0.0) {
    integral_ = 0.0;
  }
  gains_ = gains;
}

void FeedbackController::reset() noexcept {
  integral_ = 0.0;
  prev_error_ = 0.0;
  d_state_ = 0.0;
  has_prev_ = false;
}

double FeedbackController::update(double error_m, double u_ff_V, double dt_s) noexcept {
  if (!std::isfinite(error_m) || !(dt_s > 0.0)) return 0.0;
  const double inv_gain = 1.0 / gains_.nominal_gain_m_per_V;

  // Filtered derivative (backward difference through a first-order low-pass).
  if (gains_.kd > 0.0 && has_prev_) {
    const double raw = (error_m - prev_error_) / dt_s;
    const double a = dt_s / (dt_s + 1.0 / (2.0 * std::numbers::pi * gains_.d_filter_hz));
    d_state_ += a * (raw - d_state_);
  }
  prev_error_ = error_m;
  has_prev_ = true;

  const double u_pd = (gains_.kp * error_m + gains_.kd * d_state_) * inv_gain;
  const double candidate = integral_ + error_m * dt_s;
  const double u_total = u_ff_V + u_pd + gains_.ki * candidate * inv_gain;
  // Conditional integration: integrate unless it pushes further into saturation.
  const bool saturating_high = u_total > gains_.u_max_V && error_m > 0.0;
  const bool saturating_low = u_total < gains_.u_min_V && error_m < 0.0;
  if (gains_.ki > 0.0 && !saturating_high && !saturating_low) integral_ = candidate;
  return u_pd + gains_.ki * integral_ * inv_gain;
}

}  // namespace hystloop
