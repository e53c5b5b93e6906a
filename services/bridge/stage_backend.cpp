#include "bridge/stage_backend.hpp"

#include "bridge/comedi_backend.hpp"
#include "loop/bridge_core.hpp"

namespace hystloop {

SimulatedBackend::SimulatedBackend(std::string name, const SimulatedStageConfig& config)
    : name_(std::move(name)), stage_(config) {}

StageReading SimulatedBackend::step(double u_V, double t_s, double dt_s) noexcept {
  const double y_m = stage_.step(u_V, t_s, dt_s);
  return {y_m, stage_.true_position_m(), sample_flags::kSimulated};
}

std::unique_ptr<StageBackend> make_stage_backend(const std::string& name, SimulatedStageConfig config) {
  config.plant = parse_plant_kind(name, "bridge.backend");  // throws for an unknown name
  return std::make_unique<SimulatedBackend>(name, config);
}

std::unique_ptr<StageBackend> make_stage_backend(const BridgeSettings& settings) {
  // A hardware backend is added here, under its bridge.backend name.
  if (settings.backend == "comedi") return std::make_unique<ComediBackend>(settings.comedi, settings.limits);
  return make_stage_backend(settings.backend, settings.stage);
}

}  // namespace hystloop
