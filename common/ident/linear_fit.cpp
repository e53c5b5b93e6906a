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

LeastSquaresLine least_squares_line(std::span<const double> x, std::span<const double> y) noexcept {
  double sx = 0.0, sy = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) sx += x[k], sy += y[k];
  const double n = static_cast<double>(x.size()), mx = sx / n, my = sy / n;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) sxx += (x[k] - mx) * (x[k] - mx), sxy += (x[k] - mx) * (y[k] - my);
  LeastSquaresLine line;
  line.slope = sxy / sxx;
  line.offset = my - line.slope * mx;
  double ss = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) ss += std::pow(y[k] - line.slope * x[k] - line.offset, 2);
  line.residual_rms = std::sqrt(ss / n);
  line.slope_standard_error = std::sqrt(ss / (n - 2.0) / sxx);
  return line;
}

LinearFitResult fit_linear(std::span<const double> u, std::span<const double> y, double min_range) {
  LinearFitResult r;
  // (A moving u has at least 2 samples.)
  if (FitCheck c = check_fit_input(u, y, min_range); !c.ok()) return with_status(std::move(r), c.status, c.reason);
  const LeastSquaresLine line = least_squares_line(u, y);
  r.gain_m_per_V = line.slope;
  r.offset_m = line.offset;
  r.residual_rms_m = line.residual_rms;
  r.samples_used = u.size();
  if (!(r.gain_m_per_V > 0.0)) {
    const std::string reason = "gain " + std::to_string(r.gain_m_per_V) + " m/V: must be > 0";
    return with_status(std::move(r), FitStatus::out_of_range, reason);
  }
  return with_status(std::move(r), FitStatus::ok);
}

}  // namespace hystloop
