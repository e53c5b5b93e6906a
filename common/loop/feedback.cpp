#include "loop/feedback.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace hystloop {
namespace {

NotchFilter make_notch(const FeedbackGains& g) {
  return g.has_notch() ? NotchFilter(design_notch(g.notch_hz, g.notch_q, g.tick_rate_hz)) : NotchFilter();
}

bool same_notch(const FeedbackGains& a, const FeedbackGains& b) {
  if (!a.has_notch() && !b.has_notch()) return true;
  return a.notch_hz == b.notch_hz && a.notch_q == b.notch_q && a.tick_rate_hz == b.tick_rate_hz;
}

}  // namespace

void FeedbackGains::validate() const {
  require_non_negative("servo.kp", kp);
  require_non_negative("servo.ki", ki);
  require_non_negative("servo.kd", kd);
  require_positive("servo.nominal_gain_m_per_V", nominal_gain_m_per_V);
  require_finite("servo.u_min_V", u_min_V);
  require_finite("servo.u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("servo.u_max_V", "must be greater than servo.u_min_V");
  require_positive("servo.d_filter_hz", d_filter_hz);
  require_positive("servo.tick_rate_hz", tick_rate_hz);
  require_non_negative("servo.notch_hz", notch_hz);
  if (has_notch()) {
    const double max_hz = kNotchMaxFractionOfRate * tick_rate_hz;
    if (!(notch_hz < max_hz)) {
      throw ParameterError("servo.notch_hz", "must be 0 (no notch) or below 0.45 x the tick rate (" +
                                                 number_text(max_hz) + " Hz) (got " + number_text(notch_hz) + ")");
    }
    require_in_range("servo.notch_q", notch_q, kNotchMinQ, kNotchMaxQ);
  }
}

double FeedbackGains::max_kd_s() const noexcept {
  return kMaxServoKdStepGain * (1.0 / tick_rate_hz + 1.0 / (2.0 * std::numbers::pi * d_filter_hz));
}

void FeedbackGains::check_bounds(std::string_view prefix) const {
  validate();
  const auto refuse = [&](const char* name, double value, double bound, const char* unit, const char* why) {
    throw ParameterError(std::string(prefix) + name,
                         "must be <= " + number_text(bound) + unit + " (got " + number_text(value) + "): " + why);
  };
  if (!(kp <= max_kp())) {
    refuse("kp", kp, max_kp(), "",
           "above it a proportional servo over-corrects the error by more than itself each tick on a stage that "
           "follows within a tick (Banning's stage is stable up to 0.4 without the notch)");
  }
  if (!(ki <= max_ki_per_s())) {
    refuse("ki", ki, max_ki_per_s(), " 1/s",
           "ki dt <= 1 at the tick rate: above it the integral takes in more than a tick's error per tick");
  }
  if (!(kd <= max_kd_s())) {
    refuse("kd", kd, max_kd_s(), " s",
           "kd / (dt + 1 / (2 pi d_filter_hz)) <= 2: above it the filtered derivative alone over-corrects an error "
           "step on its first tick more than kp may");
  }
}

FeedbackController::FeedbackController(const FeedbackGains& gains) : gains_(gains) {
  gains_.validate();
  notch_ = make_notch(gains_);
}

void FeedbackController::set_gains(const FeedbackGains& gains) {
  gains.check_bounds();
  // Keep ki * integral constant so the integral part of the output does not jump.
  if (gains.ki > 0.0 && gains_.ki > 0.0) {
    integral_ *= gains_.ki / gains.ki;
  } else if (gains.ki == 0.0) {
    integral_ = 0.0;
  }
  if (!same_notch(gains, gains_)) {
    // A new filter with the old one's state would ring; one settled at the last output goes on
    // from it: its next output is output + b0 (x - output), x the PID part (near the output on a
    // servo in operation, whose correction is slow against the resonance).
    notch_ = make_notch(gains);
    notch_.settle_at(output_V_);
  }
  gains_ = gains;
}

void FeedbackController::reset() noexcept {
  integral_ = 0.0;
  prev_error_ = 0.0;
  d_state_ = 0.0;
  output_V_ = 0.0;
  notch_.reset();
  has_prev_ = false;
}

double FeedbackController::update(double error_m, double u_ff_V, double dt_s, double u_lo_V, double u_hi_V) noexcept {
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

  const bool notch = gains_.has_notch();
  const double u_pd = (gains_.kp * error_m + gains_.kd * d_state_) * inv_gain;
  if (gains_.ki > 0.0 && error_m != 0.0) {
    // The total command for an integral I: u_ff + b0 (u_pd + ki I / gain) + s1 (the notch's next
    // output; b0 = 1 and s1 = 0 without one), increasing in I.
    const double b0 = notch ? notch_.coefficients().b0 : 1.0;
    const double s1 = notch ? notch_.peek(0.0) : 0.0;
    const auto command_V = [&](double integral) { return u_ff_V + b0 * (u_pd + gains_.ki * integral * inv_gain) + s1; };
    const double candidate = integral_ + error_m * dt_s;
    // The edge of what will be let through in the direction the integral moves, kBoundaryMargin_V
    // inside, so that rounding never has the clamp act on a command the integrator just moved.
    const double limit_V = error_m > 0.0 ? u_hi_V : u_lo_V;
    const double margin_V = kBoundaryMargin_V * (1.0 + std::abs(limit_V));
    const double edge_V = error_m > 0.0 ? limit_V - margin_V : limit_V + margin_V;
    if (error_m > 0.0 ? command_V(candidate) <= edge_V : command_V(candidate) >= edge_V) {
      integral_ = candidate;
    } else {
      // Conditional integration: the integral moves toward the edge, never past it; nor back, when
      // the command is beyond it already. Holding it instead would freeze it whenever one tick's
      // growth is more than the slew limit's step.
      const double at_edge = ((edge_V - u_ff_V - s1) / b0 - u_pd) * gains_.nominal_gain_m_per_V / gains_.ki;
      integral_ = error_m > 0.0 ? std::max(integral_, std::min(candidate, at_edge))
                                : std::min(integral_, std::max(candidate, at_edge));
    }
  }
  const double pid = u_pd + gains_.ki * integral_ * inv_gain;
  output_V_ = notch ? notch_.step(pid) : pid;
  return output_V_;
}

}  // namespace hystloop
