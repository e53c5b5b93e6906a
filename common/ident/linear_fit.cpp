#include "ident/linear_fit.hpp"

#include <cmath>

#include "ident/fit_checks.hpp"
#include "ident/fit_clock.hpp"

namespace hystloop {

LinearParams to_linear_params(const LinearFitResult& fit) {
  LinearParams p;
  p.gain = fit.gain_m_per_V;
  p.offset = fit.offset_m;
  p.validate();
  return p;
}

LinearFitResult fit_linear(std::span<const double> u, std::span<const double> y, double min_range) {
  LinearFitResult r;
  // (A moving u has at least 2 samples.)
  if (FitCheck c = check_fit_input(u, y, min_range); !c.ok()) return with_status(std::move(r), c.status, c.reason);
  double su = 0.0, sy = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) su += u[k], sy += y[k];
  const double n = static_cast<double>(u.size()), mu = su / n, my = sy / n;
  double suu = 0.0, suy = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) suu += (u[k] - mu) * (u[k] - mu), suy += (u[k] - mu) * (y[k] - my);
  r.gain_m_per_V = suy / suu;
  r.offset_m = my - r.gain_m_per_V * mu;
  double ss = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) ss += std::pow(y[k] - r.gain_m_per_V * u[k] - r.offset_m, 2);
  r.residual_rms_m = std::sqrt(ss / n);
  r.samples_used = u.size();
  if (!(r.gain_m_per_V > 0.0)) {
    const std::string reason = "gain " + std::to_string(r.gain_m_per_V) + " m/V: must be > 0";
    return with_status(std::move(r), FitStatus::out_of_range, reason);
  }
  return with_status(std::move(r), FitStatus::ok);
}

}  // namespace hystloop
