#pragma once
// The built-in plant of an XY(Z) stage: per axis a SimulatedStage with its own parameters, drift
// and sensor noise, and a coupling matrix on the outputs (models/axis_coupling.hpp):
//
//   y_j = sum_i C_ji s_i + n_j,
//
// s_i the axis's own (hysteretic, dynamic) displacement, n_j axis j's sensor noise. The coupling
// acts on the displacements, not on the noisy readings: a sensor's noise is its own and does not
// leak into the other axes' readings. Stepped with time as an argument, like SimulatedStage.

#include <array>
#include <span>

#include "loop/simulated_stage.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

struct MultiAxisStageConfig {
  // axis[i] for i < coupling.n(): each axis's plant, drift and sensor noise, with its own seed
  // (validate() refuses two noisy axes with one seed: they would draw the same noise).
  std::array<SimulatedStageConfig, kMaxAxes> axis{};
  AxisCoupling coupling{};  // its n() is the number of axes; one uncoupled axis by default

  int axes() const noexcept { return coupling.n(); }
  void validate() const;  // throws ParameterError naming the field ("axis[1].bridge.noise_rms_m")
};

// The default XY(Z) stage: Banning's stage on every axis, 1 nm sensor noise, seeds 1, 2, 3, and
// x moving y by `x_to_y` (and z by the same fraction of x and y when n = 3), as flexure stages do.
MultiAxisStageConfig flexure_stage(int n, double x_to_y = 0.03);

class MultiAxisStage {
 public:
  explicit MultiAxisStage(const MultiAxisStageConfig& config);

  // Applies u_V[i] [V] to axis i over [t, t + dt] and writes the axes' readings [m] at its end to
  // y_m[i]; both spans hold axes() entries (entries past it are not touched). Allocation- and
  // throw-free.
  void step(std::span<const double> u_V, double t_s, double dt_s, std::span<double> y_m) noexcept;

  int axes() const noexcept { return config_.axes(); }
  // Axis i's own displacement s_i [m] after the last step (no coupling, no noise).
  double displacement_m(int axis) const noexcept { return stages_[static_cast<std::size_t>(axis)].true_position_m(); }
  // Axis j's true position [m]: its reading without the noise, (C s)_j.
  double true_position_m(int axis) const noexcept { return true_[axis]; }
  // Axis i's gain relative to its start (its drift).
  double gain_scale(int axis) const noexcept { return stages_[static_cast<std::size_t>(axis)].gain_scale(); }
  const MultiAxisStageConfig& config() const noexcept { return config_; }

 private:
  MultiAxisStageConfig config_;
  std::array<SimulatedStage, kMaxAxes> stages_;
  AxisVector true_ = AxisVector::Zero();
};

}  // namespace hystloop
