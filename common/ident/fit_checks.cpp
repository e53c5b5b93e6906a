#include "ident/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <vector>
#include <sstream>

#include "core/errors.hpp"
#include "ident/branches.hpp"

namespace hystloop {

FitCheck check_fit_samples(std::span<const double> u, std::span<const double> y) {
  if (u.size() != y.size() || u.empty()) {
    std::ostringstream s;
    s << "u has " << u.size() << " samples, y has " << y.size();
    return FitCheck{FitStatus::size_mismatch, s.str()};
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (!std::isfinite(u[k]) || !std::isfinite(y[k])) {
      std::ostringstream s;
      s << "sample " << k << " is not finite (u = " << u[k] << ", y = " << y[k] << ")";
      return FitCheck{FitStatus::non_finite_data, s.str()};
    }
    if (std::abs(u[k]) > kFitMaxAbsVoltage_V || std::abs(y[k]) > kFitMaxAbsPosition_m) {
      const bool bad_u = std::abs(u[k]) > kFitMaxAbsVoltage_V;
      std::ostringstream s;
      s << "sample " << k << ": " << (bad_u ? "u = " : "y = ") << (bad_u ? u[k] : y[k]) << (bad_u ? " V" : " m")
        << " is beyond the sanity bound +-" << (bad_u ? kFitMaxAbsVoltage_V : kFitMaxAbsPosition_m)
        << (bad_u ? " V" : " m") << " (u in volts, y in metres?)";
      return FitCheck{FitStatus::out_of_range, s.str()};
    }
  }
  return {};
}

FitCheck check_fit_input(std::span<const double> u, std::span<const double> y, double min_input_range_V,
                         double* u_min_V, double* u_max_V) {
  if (FitCheck c = check_fit_samples(u, y); !c.ok()) return c;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  if (!(*hi - *lo >= min_input_range_V) || *hi == *lo) {
    std::ostringstream s;
    s << "u spans " << (*hi - *lo) << " V (< " << min_input_range_V << " V): nothing to identify";
    return FitCheck{FitStatus::constant_input, s.str()};
  }
  if (u_min_V != nullptr) *u_min_V = *lo;
  if (u_max_V != nullptr) *u_max_V = *hi;
  return {};
}

FitCheck check_after_second_reversal(std::span<const double> u, std::size_t min_samples, std::size_t* begin) {
  const std::vector<std::size_t> rev = find_reversals(u);
  if (rev.size() < 2) {
    return FitCheck{FitStatus::too_few_branches, std::to_string(rev.size()) +
                                                     " reversals of u: need 2 (before the second the operators carry "
                                                     "their unknown initial state)"};
  }
  const std::size_t scored = u.size() - rev[1];
  if (scored < min_samples) {
    return FitCheck{FitStatus::too_few_samples, std::to_string(scored) + " samples after the second reversal (need " +
                                                    std::to_string(min_samples) + ")"};
  }
  *begin = rev[1];
  return {};
}

FitCheck check_fit_residual(double residual_rms_m, double y_span_m) {
  if (!std::isfinite(residual_rms_m) || residual_rms_m < 0.0) {
    std::ostringstream s;
    s << "the fit's residual is " << residual_rms_m << ": no usable solution";
    return FitCheck{FitStatus::solver_failure, s.str()};
  }
  if (residual_rms_m > y_span_m) {
    std::ostringstream s;
    s << "the fit's residual " << residual_rms_m << " m RMS exceeds the data's span " << y_span_m
      << " m: the model explains nothing";
    return FitCheck{FitStatus::out_of_range, s.str()};
  }
  return {};
}

FitCheck check_katalenic_params(const KatalenicParams& params, double u_span_V) {
  if (FitCheck c = check_valid(params, "Katalenic parameters outside their domain: "); !c.ok()) return c;
  std::ostringstream s;
  if (!(params.k1 <= u_span_V)) {
    s << "k1 = " << params.k1 << " V exceeds the input span " << u_span_V
      << " V: a band that wide never moves, so the data do not determine it";
    return FitCheck{FitStatus::out_of_range, s.str()};
  }
  const double sharpness = params.k2 * u_span_V;
  if (!(sharpness >= 1e-6 && sharpness <= 1e6)) {
    s << "k2 = " << params.k2 << " 1/V times the input span " << u_span_V << " V is " << sharpness
      << " (outside [1e-6, 1e6]): the transition cannot be told from a line or a corner";
    return FitCheck{FitStatus::out_of_range, s.str()};
  }
  return {};
}

}  // namespace hystloop
