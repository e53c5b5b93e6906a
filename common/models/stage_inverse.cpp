#include "models/stage_inverse.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include <Eigen/LU>  // determinant

#include "core/errors.hpp"

namespace hystloop {

double DiscreteStage::magnitude(double f_hz, double dt_s) const noexcept {
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f_hz * dt_s);
  return std::abs((b1 * z + b2) / (z * z + a1 * z + a2));
}

DiscreteStage discretise_zoh(const SecondOrderStageParams& stage, double dt_s) {
  stage.validate();
  require_in_range("dt_s", dt_s, 1e-7, 1.0);
  const ZohMatrices z = zoh_matrices(stage, dt_s);  // the matrices SecondOrderStage steps with
  const Eigen::Matrix2d& phi = z.phi;
  const Eigen::Vector2d& gamma = z.gamma;
  // G(z) = C (zI - Phi)^-1 Gamma with C = [1 0]: C adj(zI - Phi) = [z - Phi22, Phi12].
  DiscreteStage d;
  d.a1 = -phi.trace();
  d.a2 = phi.determinant();
  d.b1 = gamma(0);
  d.b2 = -phi(1, 1) * gamma(0) + phi(0, 1) * gamma(1);
  return d;
}

void StageModel::validate(double dt_s) const {
  if (kind == Kind::kNone) return;
  if (kind != Kind::kSecondOrder) throw ParameterError("stage.kind", "must be none or second_order");
  validate_within("stage.", [&] { second_order.validate(); });
  const StageInverse check(second_order, dt_s);
}

StageInverse::StageInverse(const SecondOrderStageParams& stage, double dt_s)
    : params_(stage), model_(discretise_zoh(stage, dt_s)) {
  const double z0 = model_.sampling_zero();
  if (!(model_.b1 > 0.0) || !std::isfinite(z0) || std::abs(z0) > kMaxSamplingZero) {
    throw ParameterError("stage.c", "the stage (k " + std::to_string(stage.k) + " 1/s^2, c " + std::to_string(stage.c) +
                                        " 1/s) sampled at " + std::to_string(dt_s) +
                                        " s has its sampling zero at z = " + std::to_string(z0) +
                                        "; its inverse would ring at half the tick rate (|z| > " +
                                        std::to_string(kMaxSamplingZero) +
                                        "): check the damping c, or run the feedforward without the stage");
  }
  reset(0.0);
}

void StageInverse::reset(double y0) noexcept {
  r1_ = y0;
  r2_ = y0;
  w_prev_ = y0;
}

double StageInverse::step(double r_k) noexcept {
  if (!std::isfinite(r_k)) return w_prev_;
  const double w = (r_k + model_.a1 * r1_ + model_.a2 * r2_ - model_.b2 * w_prev_) / model_.b1;
  r2_ = r1_;
  r1_ = r_k;
  w_prev_ = w;
  return w;
}

}  // namespace hystloop
