#include "ctl_servo_check.hpp"

#include <cmath>

#include <spdlog/fmt/fmt.h>

namespace hystloop::ctl {

std::optional<ServoLoopModel> servo_loop_model(const StageModel& stage, double dt_s, int extra_delay_ticks) {
  ServoLoopModel m;
  m.dt_s = dt_s;
  m.extra_delay_ticks = extra_delay_ticks;
  if (stage.is_linear()) {
    m.linear = stage.linear;
  } else if (stage.is_second_order()) {
    m.stage = stage.second_order;
  } else {
    return std::nullopt;
  }
  m.validate();
  return m;
}

FeedbackGains servo_gains(const ServoGainsFigures& gains) {
  FeedbackGains g;
  g.kp = gains.kp;
  g.ki = gains.ki_per_s;
  g.kd = gains.kd_s;
  // A Q of 0 is a bridge that reports none for a notch that is off (older builds): the default.
  g.notch_hz = gains.notch_hz;
  if (gains.notch_q > 0.0) g.notch_q = gains.notch_q;
  g.notch2_hz = gains.notch2_hz;
  if (gains.notch2_q > 0.0) g.notch2_q = gains.notch2_q;
  return g;
}

ServoCheck check_servo(const ServoGainsFigures& gains, const ServoLoopModel& model) {
  const FeedbackGains g = servo_gains(gains);
  ServoCheck c;
  c.margins = ServoLoopResponse(g, model).margins();
  const LoopMargins& m = c.margins;
  if (!m.stable) {
    c.warnings.push_back(
        fmt::format("the loop is UNSTABLE on this stage (closed-loop pole at radius {:.4f})", m.max_pole_radius));
    return c;  // margins of an unstable loop mislead
  }
  if (m.gain_margin_dB < kMinGainMargin_dB) {
    c.warnings.push_back(fmt::format("gain margin {:.1f} dB at {:.4g} Hz is under {:g} dB", m.gain_margin_dB,
                                     m.gain_margin_hz, kMinGainMargin_dB));
  }
  if (m.phase_margin_deg < kMinPhaseMargin_deg) {
    c.warnings.push_back(fmt::format("phase margin {:.1f} deg at {:.4g} Hz is under {:g} deg", m.phase_margin_deg,
                                     m.crossover_hz, kMinPhaseMargin_deg));
  }
  return c;
}

std::string describe_margins(const LoopMargins& m) {
  const auto at = [](double hz) { return std::isnan(hz) ? std::string() : fmt::format(" at {:.4g} Hz", hz); };
  const auto value = [](double v, const char* unit) {
    return std::isinf(v) ? std::string("none (no crossing)") : fmt::format("{:.1f} {}", v, unit);
  };
  return fmt::format("{}gain margin {}{}, phase margin {}{}, |S| peak {:.2f}{}",
                     m.stable ? "" : "UNSTABLE: ", value(m.gain_margin_dB, "dB"), at(m.gain_margin_hz),
                     value(m.phase_margin_deg, "deg"), at(m.crossover_hz), m.sensitivity_peak,
                     at(m.sensitivity_peak_hz));
}

}  // namespace hystloop::ctl
