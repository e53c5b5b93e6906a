#include "loop/simulated_stage.hpp"

#include <algorithm>

#include "core/errors.hpp"

namespace hystloop {

PlantKind parse_plant_kind(const std::string& name, const std::string& field) {
  if (name == "sim" || name == "banning") return PlantKind::kBanning;
  if (name == "ro" || name == "ramberg-osgood") return PlantKind::kRambergOsgood;
  throw ParameterError(field, "unknown backend '" + name + "' (expected sim or ro)");
}

void SimulatedStageConfig::validate() const {
  banning.validate();
  ramberg_osgood.validate();
  require_in_range("bridge.noise_rms_m", noise_rms_m, 0.0, 1e-6);
  require_in_range("bridge.drift_fraction", drift_fraction, -0.5, 1.0);
  require_finite("bridge.drift_start_s", drift_start_s);
  require_positive("bridge.drift_duration_s", drift_duration_s);
}

SimulatedStage::SimulatedStage(const SimulatedStageConfig& config)
    : config_((config.validate(), config)),
      banning_(config.banning),
      ramberg_osgood_(config.ramberg_osgood),
      rng_(config.seed),
      noise_(0.0, config.noise_rms_m) {}

double SimulatedStage::step(double u_V, double t_s, double dt_s) noexcept {
  const double progress = std::clamp((t_s - config_.drift_start_s) / config_.drift_duration_s, 0.0, 1.0);
  scale_ = 1.0 + config_.drift_fraction * progress;
  if (config_.plant == PlantKind::kBanning) {
    banning_.set_gain_scale(scale_);
    y_true_ = banning_.step(u_V, dt_s);
  } else {
    y_true_ = scale_ * ramberg_osgood_.forward(u_V);
  }
  return config_.noise_rms_m > 0.0 ? y_true_ + noise_(rng_) : y_true_;
}

}  // namespace hystloop
