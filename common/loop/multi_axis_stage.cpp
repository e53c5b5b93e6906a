#include "loop/multi_axis_stage.hpp"

#include <cassert>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

void MultiAxisStageConfig::validate() const {
  coupling.validate();
  for (int i = 0; i < axes(); ++i) {
    const SimulatedStageConfig& a = axis[static_cast<std::size_t>(i)];
    validate_within("axis[" + std::to_string(i) + "].", [&] { a.validate(); });
    for (int j = 0; j < i; ++j) {
      const SimulatedStageConfig& b = axis[static_cast<std::size_t>(j)];
      if (a.noise_rms_m > 0.0 && b.noise_rms_m > 0.0 && a.seed == b.seed) {
        throw ParameterError("axis[" + std::to_string(i) + "].seed", "must differ from axis[" + std::to_string(j) +
                                                                         "]'s (" + std::to_string(a.seed) +
                                                                         "): two sensors would draw the same noise");
      }
    }
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
  assert(u_V.size() >= static_cast<std::size_t>(n) && y_m.size() >= static_cast<std::size_t>(n));
  AxisVector s = AxisVector::Zero();
  for (int i = 0; i < n; ++i) {
    SimulatedStage& stage = stages_[static_cast<std::size_t>(i)];
    y_m[static_cast<std::size_t>(i)] = stage.step(u_V[static_cast<std::size_t>(i)], t_s, dt_s);  // s_i + n_i
    s[i] = stage.true_position_m();
  }
  // Each reading gains what the other axes' displacements do to it (C's diagonal is 1): an
  // uncoupled axis's reading is its own stage's, bit for bit.
  const AxisMatrix& c = config_.coupling.matrix();
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (i != j) y_m[static_cast<std::size_t>(j)] += c(j, i) * s[i];
    }
  }
  true_ = config_.coupling.couple(s);
}

}  // namespace hystloop
