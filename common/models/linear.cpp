#include "models/linear.hpp"

#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "models/mem.hpp"

namespace hystloop {

void LinearParams::validate() const {
  require_finite("gain", gain);
  if (gain == 0.0) throw ParameterError("gain", "must be != 0 (got 0)");
  require_finite("offset", offset);
}

LinearParams linear_params_from_mem(const MemParams& mem, double u_amplitude) {
  mem.validate();
  require_positive("u_amplitude", u_amplitude);
  // The major loop's ends are +-F(2A)/2 (the reversal at -A starts a branch F(p) up to +A).
  LinearParams p;
  p.gain = mem.branch_rise(2.0 * u_amplitude) / (2.0 * u_amplitude);
  p.offset = 0.0;
  return p;
}

double LinearModel::forward(double u) noexcept {
  if (!std::isfinite(u)) return std::numeric_limits<double>::quiet_NaN();
  x_ = u;
  return params_.gain * u + params_.offset + shift_;
}

void LinearModel::set_params(const LinearParams& params) {
  params.validate();
  const double y = params_.gain * x_ + params_.offset + shift_;
  params_ = params;
  shift_ = y - (params_.gain * x_ + params_.offset);
}

double LinearInverse::inverse(double y_ref) noexcept {
  if (!std::isfinite(y_ref)) return std::numeric_limits<double>::quiet_NaN();
  x_ = y_ref;
  return (y_ref - params_.offset - shift_) / params_.gain;
}

void LinearInverse::set_params(const LinearParams& params) {
  params.validate();
  const double u = (x_ - params_.offset - shift_) / params_.gain;
  params_ = params;
  shift_ = x_ - params_.offset - params_.gain * u;
}

}  // namespace hystloop
