#include "loop/compensator_config.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

double lowest_linear_feature_hz(const StageModel& stage, double dt_s) {
  if (!stage.is_linear()) return 0.0;
  constexpr double kLightDamping = 0.5;  // a pole or zero pair damped more bends |T| by at most 1.25 dB
  return stage.lowest_resonance_rad_s(dt_s, true, kLightDamping) / (2.0 * std::numbers::pi);
}

LearningConfig learning_for_stage(const LearningConfig& learning, const StageModel& stage, double dt_s) {
  LearningConfig l = learning;
  const double feature_hz = lowest_linear_feature_hz(stage, dt_s);
  if (feature_hz > 0.0) {
    const double known_hz =
        std::max(kLearningShareOfResonance * feature_hz, kLearningShareOfKnownBand * stage.known_to_hz);
    l.cutoff_hz = std::max(std::min(l.cutoff_hz, known_hz), 1.0 / l.max_period_s);
  }
  return l;
}

double resonance_corner_s(const StageModel& stage) noexcept {
  if (stage.is_second_order()) return 2.0 * 2.0 * std::numbers::pi / stage.second_order.natural_frequency();
  if (!stage.is_linear()) return 0.0;
  try {
    // Poles up to 50 kHz sampled without aliasing: |ln z| / dt is the pole's own frequency.
    const double w = stage.lowest_resonance_rad_s(1e-5);
    return w > 0.0 ? 2.0 * 2.0 * std::numbers::pi / w : 0.0;
  } catch (const ParameterError&) {  // validated where it entered: not reached
    return 0.0;
  }
}

void CompensatorConfig::validate() const {
  if (mode == FeedforwardMode::kExperiment) {
    throw ParameterError("compensator.mode", "'experiment' is started through HX_CONTROL, not selected as a mode");
  }
  OnlineModels::for_each([&]<class D>() { (models.*D::in_set).validate(); });
  require_in_range("compensator.dt_s", dt_s, 1e-6, 1.0);
  require_finite("compensator.u_min_V", u_min_V);
  require_finite("compensator.u_max_V", u_max_V);
  if (!(u_min_V < u_max_V)) throw ParameterError("compensator.u_max_V", "must exceed u_min_V");
  require_positive("compensator.slew_V_per_s", slew_V_per_s);
  require_in_range("compensator.reanchor_ticks", static_cast<double>(reanchor_ticks), 1.0, 1000.0);
  require_in_range("compensator.reanchor_ramp_ticks", static_cast<double>(reanchor_ramp_ticks), 1.0, 100000.0);
  require_in_range("compensator.slew_fraction", slew_fraction, 1e-12, 1.0);
  require_positive("compensator.reanchor_u_rate_V_per_s", reanchor_u_rate_V_per_s);
  stage.validate(dt_s);
  learning.validate(dt_s);
  require_in_range("compensator.plan_slew_fraction", plan_slew_fraction, 0.05, 1.0);
  require_in_range("compensator.servo_slew_reserve", servo_slew_reserve, 0.0, plan_slew_fraction - 0.05);
  require_in_range("compensator.experiment_ramp_V_per_s", experiment_ramp_V_per_s, 1e-3, 1e12);
  swap_review.validate();
  if (horizon_ticks < 1 || horizon_ticks > kMaxHorizonTicks) {
    throw ParameterError("compensator.horizon_s", "must be 1 to " + std::to_string(kMaxHorizonTicks) + " ticks (got " +
                                                      std::to_string(horizon_ticks) + ")");
  }
}

}  // namespace hystloop
