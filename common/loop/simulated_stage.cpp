#include "loop/simulated_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace hystloop {

PlantKind parse_plant_kind(const std::string& name, const std::string& field) {
  if (name == "sim" || name == "banning") return PlantKind::kBanning;
  if (name == "ro" || name == "ramberg-osgood") return PlantKind::kRambergOsgood;
  if (name == "series") return PlantKind::kSeries;
  throw ParameterError(field, "unknown backend '" + name + "' (expected sim, ro or series)");
}

void SimulatedStageConfig::validate() const {
  banning.validate();
  ramberg_osgood.validate();
  require_in_range("bridge.noise_rms_m", noise_rms_m, 0.0, 1e-6);
  require_in_range("bridge.drift_fraction", drift_fraction, -0.5, 1.0);
  require_finite("bridge.drift_start_s", drift_start_s);
  require_positive("bridge.drift_duration_s", drift_duration_s);
  if (plant == PlantKind::kSeries) {
    require_in_range("tick_s", tick_s, 1e-7, 1.0);
    validate_within("plant.hysteresis.", [&] { hysteresis.validate(); });
    validate_within("plant.", [&] { linear.validate(tick_s); });  // names "stage.<field>"
  }
}

SimulatedStage::SimulatedStage(const SimulatedStageConfig& config)
    : config_((config.validate(), config)),
      banning_(config.banning),
      ramberg_osgood_(config.ramberg_osgood),
      rng_(config.seed),
      noise_(0.0, config.noise_rms_m) {
  if (config_.plant != PlantKind::kSeries) return;
  hysteresis_.emplace(config_.hysteresis);
  linear_.emplace(discretise(config_.linear, config_.tick_s));
  // At rest at u = 0: the stage already at what the hysteresis gives there (an offset, a
  // Katalenic initial_offset), so that the first ticks show no step the plant did not take.
  HysteresisPlant at_rest = *hysteresis_;
  linear_->reset(at_rest.step(0.0, config_.tick_s));
}

double SimulatedStage::step(double u_V, double t_s, double dt_s) noexcept {
  const double progress = std::clamp((t_s - config_.drift_start_s) / config_.drift_duration_s, 0.0, 1.0);
  scale_ = 1.0 + config_.drift_fraction * progress;
  if (config_.plant == PlantKind::kBanning) {
    banning_.set_gain_scale(scale_);
    y_true_ = banning_.step(u_V, dt_s);
  } else if (config_.plant == PlantKind::kRambergOsgood) {
    y_true_ = scale_ * ramberg_osgood_.forward(u_V);
  } else {
    // The stage is sampled at tick_s: any other step would be a wrong stage, so none is taken.
    if (!(std::abs(dt_s - config_.tick_s) <= 1e-9 * config_.tick_s)) return std::numeric_limits<double>::quiet_NaN();
    y_true_ = linear_->step(scale_ * hysteresis_->step(u_V, config_.tick_s));
  }
  return config_.noise_rms_m > 0.0 ? y_true_ + noise_(rng_) : y_true_;
}

}  // namespace hystloop
