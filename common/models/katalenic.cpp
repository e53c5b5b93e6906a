#include "models/katalenic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

// ---------------------------------------------------------------------------------- parameters

void KatalenicParams::validate() const {
  require_positive("k1", k1);
  require_positive("k2", k2);
  require_finite("k2_slope", k2_slope);
  if (k2_slope != 0.0) {
    require_finite("k2_domain_min", k2_domain_min);
    require_finite("k2_domain_max", k2_domain_max);
    if (!(k2_domain_min < k2_domain_max)) throw ParameterError("k2_domain_max", "must be > k2_domain_min");
    if (!(k2_min() > 0.0)) {
      throw ParameterError("k2_slope",
                           "k2(x) = k2 + k2_slope * x must stay > 0 on [k2_domain_min, k2_domain_max] (min " +
                               number_text(k2_min()) + ")");
    }
    if (!(std::abs(k2_slope) < max_k2_slope())) {
      throw ParameterError("k2_slope", "|k2_slope| must be < e * k2_min / (2 k1) = " + number_text(max_k2_slope()) +
                                           " for the operator to stay invertible (got " + number_text(k2_slope) + ")");
    }
  }
  require_in_range("initial_offset", initial_offset, -k1, k1);
  input_shaping.validate("input_shaping");
  output_shaping.validate("output_shaping");
}

double KatalenicParams::k2_at(double x) const noexcept {
  if (k2_slope == 0.0) return k2;
  return k2 + k2_slope * std::clamp(x, k2_domain_min, k2_domain_max);
}

double KatalenicParams::k2_min() const noexcept {
  if (k2_slope == 0.0) return k2;
  return std::min(k2 + k2_slope * k2_domain_min, k2 + k2_slope * k2_domain_max);
}

double KatalenicParams::k2_max() const noexcept {
  if (k2_slope == 0.0) return k2;
  return std::max(k2 + k2_slope * k2_domain_min, k2 + k2_slope * k2_domain_max);
}

double KatalenicParams::max_k2_slope() const noexcept { return std::numbers::e * k2_min() / (2.0 * k1); }

// ------------------------------------------------------------------------------- direct model

KatalenicModel::KatalenicModel(const KatalenicParams& params) : params_(params) {
  params_.validate();
  reset(0.0);
}

void KatalenicModel::reset(double u0) noexcept {
  if (!std::isfinite(u0)) u0 = 0.0;
  const double x0 = params_.input_shaping.apply(u0);
  const double z0 = x0 + params_.initial_offset;
  op_.reset(x0, z0);
  u_ = u0;
  y_ = params_.output_shaping.apply(z0);
}

double KatalenicModel::forward(double u) noexcept {
  if (!std::isfinite(u)) return kNaN;
  const double x = params_.input_shaping.apply(u);
  const double z = op_.apply(x, params_.k1, params_.k2_at(x));
  u_ = u;
  y_ = params_.output_shaping.apply(z);
  return y_;
}

void KatalenicModel::set_params(const KatalenicParams& params) {
  params.validate();
  params_ = params;
  const double x = params_.input_shaping.apply(u_);
  double z = params_.output_shaping.invert(y_, op_.memory().last_beta());
  z = std::clamp(z, x - params_.k1, x + params_.k1);
  op_.reset(x, z, op_.memory().direction());
  y_ = params_.output_shaping.apply(z);
}

// ------------------------------------------------------------------------------ inverse model

KatalenicInverse::KatalenicInverse(const KatalenicParams& params) : params_(params) {
  params_.validate();
  reset(0.0);
}

void KatalenicInverse::reset(double y0) noexcept {
  if (!std::isfinite(y0)) y0 = 0.0;
  z_ = params_.output_shaping.invert(y0, 0.0);
  x_ = z_ - params_.initial_offset;
  op_.reset(z_, x_);
  y_ = y0;
  u_ = params_.input_shaping.invert(x_, 0.0);
}

double KatalenicInverse::inverse(double y_ref) noexcept {
  if (!std::isfinite(y_ref)) return kNaN;
  z_ = params_.output_shaping.invert(y_ref, z_);
  x_ = op_.apply(z_, params_.k1, params_.k2_at(z_));
  y_ = y_ref;
  u_ = params_.input_shaping.invert(x_, u_);
  return u_;
}

KatalenicRates KatalenicInverse::inverse_with_rates(double y_ref, double y_ref_dot, double y_ref_ddot) noexcept {
  if (!std::isfinite(y_ref) || !std::isfinite(y_ref_dot) || !std::isfinite(y_ref_ddot)) {
    return {kNaN, kNaN, kNaN};
  }
  const ShapingFunction& out = params_.output_shaping;
  const ShapingFunction& in = params_.input_shaping;
  z_ = out.invert(y_ref, z_);
  // Chain rule through z = psi_out^{-1}(y): z' = y' / psi_out'(z), z'' = (y'' - psi_out''(z) z'^2) / psi_out'(z).
  const double d_out = out.derivative(z_);
  const double z_dot = y_ref_dot / d_out;
  const double z_ddot = (y_ref_ddot - out.second_derivative(z_) * z_dot * z_dot) / d_out;
  const OperatorRates x = op_.apply_with_rates(z_, z_dot, z_ddot, params_.k1, params_.k2_at(z_));
  x_ = x.value;
  y_ = y_ref;
  u_ = in.invert(x_, u_);
  const double d_in = in.derivative(u_);
  KatalenicRates r;
  r.u = u_;
  r.u_dot = x.rate / d_in;
  r.u_ddot = (x.acceleration - in.second_derivative(u_) * r.u_dot * r.u_dot) / d_in;
  return r;
}

void KatalenicInverse::set_params(const KatalenicParams& params) {
  params.validate();
  params_ = params;
  z_ = params_.output_shaping.invert(y_, z_);
  x_ = std::clamp(params_.input_shaping.apply(u_), z_ - params_.k1, z_ + params_.k1);
  op_.reset(z_, x_, op_.memory().direction());
  u_ = params_.input_shaping.invert(x_, u_);
}

}  // namespace hystloop
