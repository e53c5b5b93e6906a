#include "loop/servo_notches.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace hystloop {

std::vector<ModeNotch> notches_for_stage(std::span<const std::complex<double>> poles_rad_s,
                                         const std::function<std::complex<double>(double)>& response_hz,
                                         double tick_rate_hz) {
  const double dc = std::abs(response_hz(0.0));
  std::vector<ModeNotch> found;
  if (!(dc > 0.0) || !std::isfinite(dc)) return found;
  for (const std::complex<double>& p : poles_rad_s) {
    if (!(p.imag() > 0.0)) continue;  // one of each pair; real poles do not resonate
    const double w = std::abs(p);
    const double zeta = -p.real() / w;
    const double f_hz = w / (2.0 * std::numbers::pi);
    if (!(zeta < kNotchMaxDamping) || !(f_hz < kNotchMaxFractionOfRate * tick_rate_hz)) continue;
    const double peak = std::abs(response_hz(f_hz)) / dc;
    if (!(peak > 1.0)) continue;
    // |N(r w)| for a notch of quality q: |1 - r^2| / sqrt((1 - r^2)^2 + (r / q)^2); = 1 / peak at r = 1.1.
    const double r = 1.0 + kNotchDetuning;
    const double gap = std::abs(1.0 - r * r);
    const double q = r / std::sqrt(gap * gap * (peak * peak - 1.0));
    found.push_back({ServoNotch{f_hz, std::clamp(q, kNotchMinQ, kNotchMaxSuggestedQ)}, zeta, peak});
  }
  std::sort(found.begin(), found.end(),
            [](const ModeNotch& a, const ModeNotch& b) { return a.peak_gain > b.peak_gain; });
  if (found.size() > kServoNotches) found.resize(kServoNotches);
  return found;
}

std::vector<ModeNotch> notches_for_stage(const LinearStageSpec& stage, double tick_rate_hz) {
  const double dt_s = 1.0 / tick_rate_hz;
  const DiscreteLinearStage d = discretise(stage, dt_s);
  std::vector<std::complex<double>> poles;
  for (Eigen::Index i = 0; i < d.poles.size(); ++i) {
    const std::complex<double> z = d.poles(i);
    if (std::abs(z) > 0.0) poles.push_back(std::log(z) / dt_s);  // 0: a fractional delay's state
  }
  // A discrete model's response is its sampled one; a continuous model's, its own.
  const bool discrete = !stage.numerator_zinv.empty();
  return notches_for_stage(
      poles, [&](double f_hz) { return discrete ? d.frequency_response(f_hz) : stage.frequency_response(f_hz); },
      tick_rate_hz);
}

void set_notches(FeedbackGains& gains, std::span<const ModeNotch> notches) noexcept {
  const ServoNotch none{0.0, 2.0};
  const ServoNotch first = notches.size() > 0 ? notches[0].notch : none;
  const ServoNotch second = notches.size() > 1 ? notches[1].notch : none;
  gains.notch_hz = first.hz;
  gains.notch_q = first.q;
  gains.notch2_hz = second.hz;
  gains.notch2_q = second.q;
}

namespace {

// The smaller margins of the loops at every slope ratio (unstable at any: not stable).
LoopMargins worst_margins(const FeedbackGains& gains, ServoLoopModel model) {
  LoopMargins worst;
  worst.stable = true;
  worst.gain_margin_dB = std::numeric_limits<double>::infinity();
  worst.phase_margin_deg = std::numeric_limits<double>::infinity();
  for (const double r : kServoDesignSlopeRatios) {
    model.slope_ratio = r;
    const LoopMargins m = ServoLoopResponse(gains, model).margins();
    worst.stable = worst.stable && m.stable;
    worst.max_pole_radius = std::max(worst.max_pole_radius, m.max_pole_radius);
    if (m.gain_margin_dB < worst.gain_margin_dB) {
      worst.gain_margin_dB = m.gain_margin_dB;
      worst.gain_margin_hz = m.gain_margin_hz;
    }
    if (m.phase_margin_deg < worst.phase_margin_deg) {
      worst.phase_margin_deg = m.phase_margin_deg;
      worst.crossover_hz = m.crossover_hz;
    }
    if (m.sensitivity_peak > worst.sensitivity_peak) {
      worst.sensitivity_peak = m.sensitivity_peak;
      worst.sensitivity_peak_hz = m.sensitivity_peak_hz;
    }
  }
  return worst;
}

bool meets_design(const LoopMargins& m) {
  return m.stable && m.gain_margin_dB >= kServoDesignGainMargin_dB && m.phase_margin_deg >= kServoDesignPhaseMargin_deg;
}

}  // namespace

StageServo servo_for_stage(const LinearStageSpec& stage, FeedbackGains base, int extra_delay_ticks) {
  StageServo out;
  out.notches = notches_for_stage(stage, base.tick_rate_hz);
  base.kp = 0.0;
  base.kd = 0.0;
  set_notches(base, out.notches);
  ServoLoopModel model;
  model.linear = stage;
  model.dt_s = 1.0 / base.tick_rate_hz;
  model.extra_delay_ticks = extra_delay_ticks;
  model.validate();
  // With kp = kd = 0 the loop gain is ki times a fixed response: the gain margin falls as 1 / ki
  // and the crossover climbs into the stage's phase lag, so the gains that meet the design are the
  // ki up to a boundary, found by bisection on log ki (to 0.5 %), rounded down to a whole 1/s.
  const auto meets = [&](double ki) {
    base.ki = ki;
    return meets_design(worst_margins(base, model));
  };
  double lo = 1.0;  // [1/s]: below it the integral takes minutes to act
  double hi = base.max_ki_per_s();
  if (!meets(lo)) {
    base.ki = 0.0;
    out.gains = base;
    return out;
  }
  if (meets(hi)) lo = hi;
  while (hi / lo > 1.005) {
    const double mid = std::sqrt(lo * hi);
    (meets(mid) ? lo : hi) = mid;
  }
  base.ki = std::floor(lo);  // a whole 1/s, as it is printed and typed (lo >= 1)
  out.gains = base;
  out.worst = worst_margins(base, model);
  return out;
}

}  // namespace hystloop
