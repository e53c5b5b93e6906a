#include "loop/multi_axis_stage.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

void MultiAxisStageConfig::validate() const {
  coupling.validate();
  for (int i = 0; i < axes(); ++i) {
    validate_within("axis[" + std::to_string(i) + "].", [&] { axis[static_cast<std::size_t>(i)].validate(); });
  }
}

MultiAxisStageConfig flexure_stage(int n, double x_to_y) {
  AxisMatrix c = AxisMatrix::Identity();
  if (n >= 2) c(1, 0) = x_to_y;
  if (n >= 3) c(2, 0) = c(2, 1) = x_to_y;
  MultiAxisStageConfig config;
  config.coupling = AxisCoupling(n, c);
  for (std::size_t i = 0; i < config.axis.size(); ++i) config.axis[i].seed = i + 1;
  return config;
}

namespace {
// An axis past n is never stepped: it gets a default stage, so that nothing the config holds for
// it (unvalidated) is used.
SimulatedStage stage_of(const MultiAxisStageConfig& c, int i) {
  return SimulatedStage(i < c.axes() ? c.axis[static_cast<std::size_t>(i)] : SimulatedStageConfig{});
}
}  // namespace

MultiAxisStage::MultiAxisStage(const MultiAxisStageConfig& config)
    : config_((config.validate(), config)), stages_{stage_of(config, 0), stage_of(config, 1), stage_of(config, 2)} {}

void MultiAxisStage::step(std::span<const double> u_V, double t_s, double dt_s, std::span<double> y_m) noexcept {
  const int n = axes();
  AxisVector s = AxisVector::Zero();
  AxisVector noise = AxisVector::Zero();
  for (int i = 0; i < n; ++i) {
    SimulatedStage& stage = stages_[static_cast<std::size_t>(i)];
    noise[i] = stage.step(u_V[static_cast<std::size_t>(i)], t_s, dt_s) - stage.true_position_m();
    s[i] = stage.true_position_m();
  }
  true_ = config_.coupling.couple(s);
  for (int j = 0; j < n; ++j) y_m[static_cast<std::size_t>(j)] = true_[j] + noise[j];
}

}  // namespace hystloop
