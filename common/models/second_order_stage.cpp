#include "models/second_order_stage.hpp"

#include <cmath>
#include <limits>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/errors.hpp"

namespace hystloop {

void SecondOrderStageParams::validate() const {
  require_positive("k", k);
  require_positive("c", c);
}

double SecondOrderStageParams::natural_frequency() const noexcept { return std::sqrt(k); }

double SecondOrderStageParams::damping_ratio() const noexcept { return c / (2.0 * std::sqrt(k)); }

SecondOrderStage::SecondOrderStage(const SecondOrderStageParams& params) : params_(params) {
  params_.validate();
  omega_n_ = params_.natural_frequency();
  reset(0.0);
}

void SecondOrderStage::reset(double y0) noexcept { x_ << y0, 0.0; }

double SecondOrderStage::velocity() const noexcept { return x_(1) * omega_n_; }

ZohMatrices zoh_matrices(const SecondOrderStageParams& params, double dt) noexcept {
  const double wn = params.natural_frequency();
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  // d/dt [y; v/wn] = [0 wn; -wn -c] [y; v/wn] + [0; wn] w
  m(0, 1) = wn;
  m(1, 0) = -wn;
  m(1, 1) = -params.c;
  m(1, 2) = wn;
  m *= dt;
  const Eigen::Matrix3d e = m.exp();
  return {e.topLeftCorner<2, 2>(), e.topRightCorner<2, 1>()};
}

void SecondOrderStage::discretise(double dt) noexcept {
  const ZohMatrices z = zoh_matrices(params_, dt);
  phi_ = z.phi;
  gamma_ = z.gamma;
  dt_cached_ = dt;
}

double SecondOrderStage::step(double w, double dt) noexcept {
  if (!std::isfinite(w) || !std::isfinite(dt) || !(dt > 0.0)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (dt != dt_cached_) discretise(dt);
  x_ = phi_ * x_ + gamma_ * w;
  return x_(0);
}

}  // namespace hystloop
