#include "models/prandtl_ishlinskii.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"
#include "models/mem.hpp"

namespace hystloop {
namespace {

std::string indexed(const char* name, std::size_t i) { return std::string(name) + "[" + std::to_string(i) + "]"; }

double play(double u, double r, double z) noexcept { return std::max(u - r, std::min(u + r, z)); }

}  // namespace

void PiParams::validate() const {
  if (count < 1 || count > kPiMaxOperators) {
    throw ParameterError("count",
                         "must be in [1, " + std::to_string(kPiMaxOperators) + "] (got " + std::to_string(count) + ")");
  }
  if (thresholds[0] != 0.0) throw ParameterError("thresholds[0]", "must be 0 (the identity operator)");
  require_positive("weights[0]", weights[0]);
  double cumulative = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    require_finite(indexed("thresholds", i), thresholds[i]);
    require_finite(indexed("weights", i), weights[i]);
    if (i > 0 && !(thresholds[i] > thresholds[i - 1])) {
      throw ParameterError(indexed("thresholds", i), "must be greater than thresholds[" + std::to_string(i - 1) + "]");
    }
    cumulative += weights[i];
    if (!(cumulative > 0.0)) {
      throw ParameterError(indexed("weights", i), "makes the cumulative weight <= 0 (the loading curve must increase)");
    }
  }
}

PiParams PiParams::with_even_thresholds(std::size_t count, double max_threshold) {
  if (count < 1 || count > kPiMaxOperators)
    throw ParameterError("count", "must be in [1, " + std::to_string(kPiMaxOperators) + "]");
  require_positive("max_threshold", max_threshold);
  PiParams p;
  p.count = count;
  for (std::size_t i = 0; i < count; ++i)
    p.thresholds[i] = max_threshold * static_cast<double>(i) / static_cast<double>(count);
  return p;
}

PiParams inverse_pi_params(const PiParams& f) {
  f.validate();
  PiParams inv;
  inv.count = f.count;
  double w_prev = 0.0;  // W_{i-1}
  double w_cum = 0.0;   // W_i
  for (std::size_t i = 0; i < f.count; ++i) {
    w_cum += f.weights[i];
    double r = 0.0;
    for (std::size_t j = 0; j <= i; ++j) r += f.weights[j] * (f.thresholds[i] - f.thresholds[j]);
    inv.thresholds[i] = r;
    inv.weights[i] = i == 0 ? 1.0 / f.weights[0] : -f.weights[i] / (w_cum * w_prev);
    w_prev = w_cum;
  }
  inv.validate();
  return inv;
}

PiParams pi_params_from_mem(const MemParams& mem, std::size_t count, double u_amplitude) {
  mem.validate();
  require_positive("u_amplitude", u_amplitude);
  PiParams p = PiParams::with_even_thresholds(count, u_amplitude);
  // Slope of the loading curve on [r_i, r_{i+1}] is the chord of the skeleton phi(r) = F(2r)/2;
  // the last segment ends at u_amplitude.
  double w_prev = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    const double a = p.thresholds[i];
    const double b = i + 1 < count ? p.thresholds[i + 1] : u_amplitude;
    const double chord = (mem.skeleton(b) - mem.skeleton(a)) / (b - a);
    p.weights[i] = chord - w_prev;
    w_prev = chord;
  }
  p.validate();
  return p;
}

// ---- PiModel -------------------------------------------------------------------------------------

PiModel::PiModel(const PiParams& params) : params_(params) {
  params_.validate();
  reset(0.0);
}

double PiModel::sum() const noexcept {
  double y = y_shift_;
  for (std::size_t i = 0; i < params_.count; ++i) y += params_.weights[i] * z_[i];
  return y;
}

void PiModel::reset(double u0) noexcept {
  z_.fill(0.0);
  y_shift_ = 0.0;
  for (std::size_t i = 0; i < params_.count; ++i) z_[i] = play(u0, params_.thresholds[i], 0.0);
  u_ = u0;
  y_ = sum();
}

double PiModel::forward(double u) noexcept {
  if (!std::isfinite(u)) return std::numeric_limits<double>::quiet_NaN();
  double y = y_shift_;
  for (std::size_t i = 0; i < params_.count; ++i) {
    z_[i] = play(u, params_.thresholds[i], z_[i]);
    y += params_.weights[i] * z_[i];
  }
  u_ = u;
  y_ = y;
  return y;
}

void PiModel::set_params(const PiParams& params) {
  params.validate();
  // Operators added beyond the old count start as if they had just been passed by u (z = u).
  for (std::size_t i = params_.count; i < params.count; ++i) z_[i] = u_;
  params_ = params;
  for (std::size_t i = 0; i < params_.count; ++i) z_[i] = play(u_, params_.thresholds[i], z_[i]);
  y_shift_ = 0.0;
  y_shift_ = y_ - sum();
}

// ---- PiInverse -----------------------------------------------------------------------------------

PiInverse::PiInverse(const PiParams& params) : params_(params), inverse_(inverse_pi_params(params)) {}

void PiInverse::set_params(const PiParams& params) {
  PiParams inv = inverse_pi_params(params);
  inverse_.set_params(inv);
  params_ = params;
}

}  // namespace hystloop
