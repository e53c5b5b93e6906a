#pragma once
// Banning et al. (2001) linear stage, eqs. (28)-(29) with Table 2: a damped mass-spring system
// in the normalised controllable realisation (unit DC gain),
//
//   d/dt [y; v] = [0 1; -k -c] [y; v] + [0; k] w,    i.e.  y'' + c y' + k y = k w.
//
// Discretisation: EXACT ZERO-ORDER HOLD. The input is held constant over each step (as the
// bridge's DAC holds the voltage), so x+ = Phi x + Gamma w with Phi = e^{A dt},
// Gamma = int_0^dt e^{A s} ds B, both read off the exponential of the augmented 3x3 matrix
// [A B; 0 0] dt (Eigen's Pade matrix exponential). The state is kept as [y, v / omega_n] so
// that every entry of that matrix is O(omega_n dt) and the exponential is well conditioned.
// Phi and Gamma are computed once per dt and cached; a step with a different dt recomputes them
// (fixed-size, no allocation). The only error is rounding; tests/models/second_order_stage_test.cpp
// compares against RK4 at a much finer step.
//
// Units: the input and output share a unit (m -> m after the hysteresis, or V -> V in the paper's
// order); k [1/s^2] = omega_n^2, c [1/s] = 2 zeta omega_n.

#include <Eigen/Core>

namespace hystloop {

struct SecondOrderStageParams {
  double k = 1.17e8;  // [1/s^2] Table 2: omega_n = 10.8e3 rad/s, i.e. 1.72 kHz
  double c = 2.03e3;  // [1/s]   Table 2: damping ratio 0.094, resonance peak ~5.3x

  void validate() const;  // throws ParameterError naming the field ("k: must be > 0 (got -1)")

  double natural_frequency() const noexcept;  // omega_n [rad/s]
  double damping_ratio() const noexcept;      // zeta [-]
};

// The exact ZOH discretisation x+ = Phi x + Gamma w of the state [y, v / omega_n] at step dt [s]
// (the exponential of the augmented matrix, every entry O(omega_n dt)). Validated by the caller.
struct ZohMatrices {
  Eigen::Matrix2d phi;
  Eigen::Vector2d gamma;
};
ZohMatrices zoh_matrices(const SecondOrderStageParams& params, double dt) noexcept;

class SecondOrderStage {
 public:
  explicit SecondOrderStage(const SecondOrderStageParams& params = {});  // validates

  // At rest at output y0 (the equilibrium for an input held at y0).
  void reset(double y0 = 0.0) noexcept;

  // Holds input w for dt [s] and returns y at the end of the interval. A non-finite w or a dt that
  // is not finite and > 0 returns NaN and leaves the state untouched.
  double step(double w, double dt) noexcept;

  const SecondOrderStageParams& params() const noexcept { return params_; }
  double output() const noexcept { return x_(0); }  // y
  double velocity() const noexcept;                 // dy/dt [unit/s]

 private:
  void discretise(double dt) noexcept;

  SecondOrderStageParams params_;
  double omega_n_ = 0.0;                         // [rad/s]
  Eigen::Vector2d x_ = Eigen::Vector2d::Zero();  // [y, v / omega_n]
  Eigen::Matrix2d phi_ = Eigen::Matrix2d::Identity();
  Eigen::Vector2d gamma_ = Eigen::Vector2d::Zero();
  double dt_cached_ = -1.0;  // [s]; < 0 until the first step
};

}  // namespace hystloop
