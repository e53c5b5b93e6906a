#include "models/banning_stage.hpp"

#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace hystloop {

void BanningStageParams::validate() const {
  validate_within("hysteresis.", [&] { hysteresis.validate(); });
  validate_within("stage.", [&] { stage.validate(); });
}

namespace {
const BanningStageParams& validated(const BanningStageParams& p) {
  p.validate();
  return p;
}

// Extreme of the cubic Hermite interpolant of y_L over one step (values y0, y1 and slopes m0, m1
// per unit step, of opposite signs): its derivative is a quadratic with exactly one root in (0, 1).
double hermite_extreme(double y0, double m0, double y1, double m1) noexcept {
  const double qa = 6.0 * (y0 - y1) + 3.0 * (m0 + m1);
  const double qb = -6.0 * (y0 - y1) - 4.0 * m0 - 2.0 * m1;
  double lo = 0.0;
  double hi = 1.0;
  for (int i = 0; i < 40; ++i) {
    const double s = 0.5 * (lo + hi);
    const double d = (qa * s + qb) * s + m0;
    ((d > 0.0) == (m0 > 0.0) ? lo : hi) = s;
  }
  const double s = 0.5 * (lo + hi);
  const double s2 = s * s;
  const double s3 = s2 * s;
  return (2.0 * s3 - 3.0 * s2 + 1.0) * y0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * y1 + (s3 - s2) * m1;
}
}  // namespace

BanningStage::BanningStage(const BanningStageParams& params)
    : params_(validated(params)), hysteresis_(params.hysteresis), stage_(params.stage) {
  reset(0.0);
}

void BanningStage::reset(double u0) noexcept {
  if (params_.order == BanningOrder::kHysteresisThenStage) {
    hysteresis_.reset(u0);
    stage_.reset(hysteresis_.output());
    y_ = gain_scale_ * stage_.output();
  } else {
    stage_.reset(u0);
    hysteresis_.reset(u0);
    y_ = gain_scale_ * hysteresis_.output();
  }
}

bool BanningStage::set_gain_scale(double scale) noexcept {
  if (!std::isfinite(scale) || !(scale > 0.0)) return false;
  gain_scale_ = scale;
  return true;
}

double BanningStage::step(double u, double dt) noexcept {
  if (!std::isfinite(u) || !std::isfinite(dt) || !(dt > 0.0)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double y = 0.0;
  if (params_.order == BanningOrder::kHysteresisThenStage) {
    y = stage_.step(hysteresis_.step(u), dt);
  } else {
    // y_L reverses inside the step when its velocity changes sign (at most once while dt is below
    // half the stage's ringing period, pi / omega_d = 290 us). Moving the rate-independent CH
    // through the reversal's extreme keeps the loop's tip: skipping it would cut the loop short.
    const double y0 = stage_.output();
    const double v0 = stage_.velocity();
    const double y1 = stage_.step(u, dt);
    const double v1 = stage_.velocity();
    if (v0 * v1 < 0.0) hysteresis_.step(hermite_extreme(y0, v0 * dt, y1, v1 * dt));
    y = hysteresis_.step(y1);
  }
  y_ = gain_scale_ * y;
  return y_;
}

}  // namespace hystloop
