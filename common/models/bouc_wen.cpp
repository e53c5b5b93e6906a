#include "models/bouc_wen.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

void BoucWenParams::validate() const {
  require_positive("d", d);
  require_positive("alpha", alpha);
  require_positive("beta", beta);
  require_finite("gamma", gamma);
  if (!(gamma > -beta && gamma <= beta)) {
    throw ParameterError("gamma",
                         "must satisfy -beta < gamma <= beta (beta + gamma > 0, beta - gamma >= 0: the bounded "
                         "class of Ikhouane et al. 2007) (got " +
                             number_text(gamma) + " with beta " + number_text(beta) + ")");
  }
  require_finite("n", n);
  if (!(n >= 1.0)) throw ParameterError("n", "must be >= 1 (got " + number_text(n) + ")");
  if (!(rk4_substeps >= 1 && rk4_substeps <= 4096)) {
    throw ParameterError("rk4_substeps", "must be in [1, 4096] (got " + std::to_string(rk4_substeps) + ")");
  }
}

double BoucWenParams::h_bound() const noexcept { return std::pow(alpha * d / (beta + gamma), 1.0 / n); }

BoucWen::BoucWen(const BoucWenParams& params) : params_(params) {
  params_.validate();
  reset(0.0);
}

void BoucWen::reset(double u0) noexcept { reset(u0, 0.0); }

void BoucWen::reset(double u0, double h0) noexcept {
  u_ = std::isfinite(u0) ? u0 : 0.0;
  h_ = std::isfinite(h0) ? h0 : 0.0;
}

void BoucWen::set_params(const BoucWenParams& params) {
  params.validate();
  params_ = params;
}

double BoucWen::step_exact(double u) const noexcept {
  const BoucWenParams& p = params_;
  const double s = u > u_ ? 1.0 : -1.0;
  const double ad = p.alpha * p.d;
  double dist = std::abs(u - u_);
  double h = h_;
  if (s * h < 0.0) {
    // Towards h = 0 with lambda = beta - gamma >= 0; it is reached after p* = ln(1 + lambda |h| / (alpha d)) / lambda.
    const double lambda = p.beta - p.gamma;
    const double reach = lambda > 0.0 ? std::log1p(lambda * std::abs(h) / ad) / lambda : std::abs(h) / ad;
    if (dist < reach) {
      if (lambda > 0.0) {
        const double h_inf = s * ad / lambda;
        return h_inf + (h - h_inf) * std::exp(-lambda * dist);
      }
      return h + s * ad * dist;
    }
    h = 0.0;
    dist -= reach;
  }
  const double lambda = p.beta + p.gamma;
  const double h_inf = s * ad / lambda;
  return h_inf + (h - h_inf) * std::exp(-lambda * dist);
}

double BoucWen::step_rk4(double u) const noexcept {
  const BoucWenParams& p = params_;
  const double s = u > u_ ? 1.0 : -1.0;
  const double sad = s * p.alpha * p.d;
  const double sg = s * p.gamma;
  // dh/dp = s alpha d - beta |h|^(n-1) h - s gamma |h|^n = s alpha d - |h|^n (beta sign(h) + s gamma).
  auto rhs = [&](double h) noexcept {
    const double hn = std::pow(std::abs(h), p.n);
    return sad - hn * (h < 0.0 ? sg - p.beta : sg + p.beta);
  };
  const double dp = std::abs(u - u_) / p.rk4_substeps;
  double h = h_;
  for (int i = 0; i < p.rk4_substeps; ++i) {
    const double k1 = rhs(h);
    const double k2 = rhs(h + 0.5 * dp * k1);
    const double k3 = rhs(h + 0.5 * dp * k2);
    const double k4 = rhs(h + dp * k3);
    h += dp / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return h;
}

double BoucWen::step(double u) noexcept {
  if (!std::isfinite(u)) return std::numeric_limits<double>::quiet_NaN();
  if (u != u_) {
    h_ = params_.n == 1.0 ? step_exact(u) : step_rk4(u);
    u_ = u;
  }
  return params_.d * u_ - h_;
}

}  // namespace hystloop
