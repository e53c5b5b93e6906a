#include "models/coleman_hodgdon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace hystloop {

void ColemanHodgdonParams::validate() const {
  require_positive("a", a);
  require_positive("b", b);
  require_positive("alpha", alpha);
  require_positive("s_max", s_max);
  // (4): g <= f' needs b <= a; (5) inside +-s_max reduces to (a - b)(1 - e^{-alpha(s_max - s)}) <= b.
  require_in_range("b", b, 0.5 * a, a);
}

double ColemanHodgdonParams::f(double s) const noexcept { return a * std::clamp(s, -s_max, s_max); }

double ColemanHodgdonParams::g(double s) const noexcept { return std::abs(s) <= s_max ? b : 0.0; }

ColemanHodgdon::ColemanHodgdon(const ColemanHodgdonParams& params) : params_(params) {
  params_.validate();
  reset(0.0);
}

void ColemanHodgdon::reset(double u0) noexcept { reset(u0, params_.f(u0)); }

void ColemanHodgdon::reset(double u0, double w0) noexcept {
  u_ = u0;
  w_ = w0;
}

void ColemanHodgdon::set_params(const ColemanHodgdonParams& params) {
  params.validate();
  params_ = params;
}

double ColemanHodgdon::relax(double u0, double u1, double w0, double sigma) const noexcept {
  // On this piece f(s) = fs * s + f0 and g(s) = g0. dw/du = -sigma alpha (w - f) + g has the
  // particular solution w_p(s) = f(s) + sigma (g0 - fs) / alpha, and
  //   w(u1) = w_p(u1) + (w0 - w_p(u0)) e^{-alpha |u1 - u0|}.
  const ColemanHodgdonParams& p = params_;
  const double mid = 0.5 * (u0 + u1);
  const bool inside = std::abs(mid) <= p.s_max;
  const double fs = inside ? p.a : 0.0;
  const double g0 = inside ? p.b : 0.0;
  const double shift = sigma * (g0 - fs) / p.alpha;
  const double wp0 = p.f(u0) + shift;
  const double wp1 = p.f(u1) + shift;
  return wp1 + (w0 - wp0) * std::exp(-p.alpha * std::abs(u1 - u0));
}

double ColemanHodgdon::step(double u) noexcept {
  if (!std::isfinite(u)) return std::numeric_limits<double>::quiet_NaN();
  if (u == u_) return w_;
  const double sigma = u > u_ ? 1.0 : -1.0;
  const double s_max = params_.s_max;
  double from = u_;
  double w = w_;
  // Cross the breakpoints -s_max, +s_max in the direction of travel, one piece at a time.
  const double breaks[2] = {sigma > 0.0 ? -s_max : s_max, sigma > 0.0 ? s_max : -s_max};
  for (double br : breaks) {
    if ((br - from) * sigma > 0.0 && (u - br) * sigma > 0.0) {
      w = relax(from, br, w, sigma);
      from = br;
    }
  }
  w = relax(from, u, w, sigma);
  u_ = u;
  w_ = w;
  return w;
}

}  // namespace hystloop
