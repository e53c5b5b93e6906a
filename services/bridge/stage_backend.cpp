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

MultiAxisSimulatedBackend::MultiAxisSimulatedBackend(std::string name, const MultiAxisStageConfig& config)
    : name_(std::move(name)), stage_(config) {}

StageReading MultiAxisSimulatedBackend::step(double u_V, double t_s, double dt_s) noexcept {
  std::array<double, kMaxAxes> u = u_last_V_;
  u[0] = u_V;
  std::array<StageReading, kMaxAxes> out{};
  step_axes(std::span(u).first(static_cast<std::size_t>(axes())), t_s, dt_s, out);
  return out[0];
}

void MultiAxisSimulatedBackend::step_axes(std::span<const double> u_V, double t_s, double dt_s,
                                          std::span<StageReading> out) noexcept {
  const auto n = static_cast<std::size_t>(axes());
  std::array<double, kMaxAxes> y{};
  stage_.step(u_V.first(n), t_s, dt_s, y);
  for (std::size_t i = 0; i < n; ++i) {
    u_last_V_[i] = u_V[i];
    out[i] = {y[i], stage_.true_position_m(static_cast<int>(i)), sample_flags::kSimulated};
  }
}

double MultiAxisSimulatedBackend::gain_scale() const noexcept { return stage_.gain_scale(0); }

std::unique_ptr<StageBackend> make_stage_backend(const std::string& name, SimulatedStageConfig config) {
  config.plant = parse_plant_kind(name, "bridge.backend");  // throws for an unknown name
  return std::make_unique<SimulatedBackend>(name, config);
}

std::unique_ptr<StageBackend> make_stage_backend(const BridgeSettings& settings) {
  // A hardware backend is added here, under its bridge.backend name.
  if (settings.backend == "comedi") {
    // One actuator per axis, each its own range and safe voltage (axes_limits() is a copy: kept here).
    const std::array<ActuatorLimits, kMaxAxes> limits = settings.axes_limits();
    return std::make_unique<ComediBackend>(
        settings.comedi, std::span<const ActuatorLimits>(limits).first(static_cast<std::size_t>(settings.axes)));
  }
  if (settings.axes == 1) return make_stage_backend(settings.backend, settings.stage);
  return std::make_unique<MultiAxisSimulatedBackend>(settings.backend, multi_axis_stage(settings));
}

}  // namespace hystloop
