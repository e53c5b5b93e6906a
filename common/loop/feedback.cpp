#include "loop/feedback.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace hystloop {
namespace {

// Notch i of g, or the identity (b0 = 1) where it is off.
NotchFilter make_notch(const FeedbackGains& g, std::size_t i) {
  const ServoNotch n = g.notch(i);
  return n.on() ? NotchFilter(design_notch(n.hz, n.q, g.tick_rate_hz)) : NotchFilter();
}

bool same_notch(const FeedbackGains& a, const FeedbackGains& b, std::size_t i) {
  const ServoNotch na = a.notch(i), nb = b.notch(i);
  if (!na.on() && !nb.on()) return true;
  return na.hz == nb.hz && na.q == nb.q && a.tick_rate_hz == b.tick_rate_hz;
}

void validate_notch(const char* hz_field, const char* q_field, const ServoNotch& n, double tick_rate_hz) {
  require_non_negative(hz_field, n.hz);
  if (!n.on()) return;
  const double max_hz = kNotchMaxFractionOfRate * tick_rate_hz;
  if (!(n.hz < max_hz)) {
    throw ParameterError(hz_field, "must be 0 (no notch) or below 0.45 x the tick rate (" + number_text(max_hz) +
                                       " Hz) (got " + number_text(n.hz) + ")");
  }
  require_in_range(q_field, n.q, kNotchMinQ, kNotchMaxQ);
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
  validate_notch("servo.notch_hz", "servo.notch_q", notch(0), tick_rate_hz);
  validate_notch("servo.notch2_hz", "servo.notch2_q", notch(1), tick_rate_hz);
}

std::string notches_text(const FeedbackGains& g) {
  std::string on;
  int count = 0;
  for (std::size_t i = 0; i < kServoNotches; ++i) {
    const ServoNotch n = g.notch(i);
    if (!n.on()) continue;
    on += (count++ == 0 ? "" : " and ") + number_text(n.hz) + " Hz (Q " + number_text(n.q) + ")";
  }
  if (count == 0) return "no notch";
  return (count == 1 ? "notch at " : "notches at ") + on;
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
  for (std::size_t i = 0; i < kServoNotches; ++i) notches_[i] = make_notch(gains_, i);
}

void FeedbackController::set_gains(const FeedbackGains& gains) {
  gains.check_bounds();
  // Keep ki * integral constant so the integral part of the output does not jump.
  if (gains.ki > 0.0 && gains_.ki > 0.0) {
    integral_ *= gains_.ki / gains.ki;
  } else if (gains.ki == 0.0) {
    integral_ = 0.0;
  }
  for (std::size_t i = 0; i < kServoNotches; ++i) {
    if (same_notch(gains, gains_, i)) continue;  // an unchanged filter keeps its state
    // A new filter with the old one's state would ring; one settled at its last output goes on
    // from it: its next output is that output + b0 (x - it), x its input (near it on a servo in
    // operation, whose correction is slow against the resonance; the gain at DC is 1).
    notches_[i] = make_notch(gains, i);
    notches_[i].settle_at(notch_out_V_[i]);
  }
  gains_ = gains;
}

void FeedbackController::reset() noexcept {
  integral_ = 0.0;
  prev_error_ = 0.0;
  d_state_ = 0.0;
  output_V_ = 0.0;
  for (NotchFilter& n : notches_) n.reset();
  notch_out_V_.fill(0.0);
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

  const double u_pd = (gains_.kp * error_m + gains_.kd * d_state_) * inv_gain;
  if (gains_.ki > 0.0 && error_m != 0.0) {
    // The total command for an integral I, on the next tick: u_ff + b0 (u_pd + ki I / gain) + s1,
    // the cascade's next output being affine in its input x: b0 x + s1 (b0 = 1 and s1 = 0 without
    // a notch: the identity filter of a notch off adds nothing, exactly); and once the notches have
    // rung out (their gain at DC is 1): u_ff + u_pd + ki I / gain. Both increase in I.
    double b0 = 1.0, s1 = 0.0;
    for (const NotchFilter& n : notches_) {
      s1 = n.peek(s1);  // n's next output for input b0 x + s1 is n.b0 b0 x + n.peek(s1)
      b0 *= n.coefficients().b0;
    }
    const auto next_V = [&](double integral) { return u_ff_V + b0 * (u_pd + gains_.ki * integral * inv_gain) + s1; };
    const auto settled_V = [&](double integral) { return u_ff_V + u_pd + gains_.ki * integral * inv_gain; };
    const double candidate = integral_ + error_m * dt_s;
    // The edge of what will be let through in the direction the integral moves, kBoundaryMargin_V
    // inside, so that rounding never has the clamp act on a command the integrator just moved.
    const double limit_V = error_m > 0.0 ? u_hi_V : u_lo_V;
    const double margin_V = kBoundaryMargin_V * (1.0 + std::abs(limit_V));
    const double edge_V = error_m > 0.0 ? limit_V - margin_V : limit_V + margin_V;
    const auto inside = [&](double command_V) { return error_m > 0.0 ? command_V <= edge_V : command_V >= edge_V; };
    if (inside(next_V(candidate)) && inside(settled_V(candidate))) {
      integral_ = candidate;
    } else {
      // Conditional integration: the integral moves toward the edge, never past it; nor back, when
      // the command is beyond it already. Holding it instead would freeze it whenever one tick's
      // growth is more than the slew limit's step. Past it means either way: the next output
      // alone would let the integral climb in the troughs of a notch's ringing, tick by tick,
      // until the settled command sat far beyond the edge (a wind-up the clamp then hides).
      const double next_edge = ((edge_V - u_ff_V - s1) / b0 - u_pd) * gains_.nominal_gain_m_per_V / gains_.ki;
      const double settled_edge = (edge_V - u_ff_V - u_pd) * gains_.nominal_gain_m_per_V / gains_.ki;
      integral_ = error_m > 0.0 ? std::max(integral_, std::min({candidate, next_edge, settled_edge}))
                                : std::min(integral_, std::max({candidate, next_edge, settled_edge}));
    }
  }
  const double pid = u_pd + gains_.ki * integral_ * inv_gain;
  double out = pid;
  for (std::size_t i = 0; i < kServoNotches; ++i) out = notch_out_V_[i] = notches_[i].step(out);
  output_V_ = out;
  return output_V_;
}

}  // namespace hystloop
