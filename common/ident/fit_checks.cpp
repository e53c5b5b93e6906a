#include "ident/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <vector>
#include <fmt/format.h>

#include "core/errors.hpp"
#include "ident/branches.hpp"

namespace hystloop {

FitCheck check_fit_samples(std::span<const double> u, std::span<const double> y) {
  if (u.size() != y.size() || u.empty()) {
    return FitCheck{FitStatus::size_mismatch, fmt::format("u has {} samples, y has {}", u.size(), y.size())};
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (!std::isfinite(u[k]) || !std::isfinite(y[k])) {
      return FitCheck{FitStatus::non_finite_data,
                      fmt::format("sample {} is not finite (u = {:g}, y = {:g})", k, u[k], y[k])};
    }
    if (std::abs(u[k]) > kFitMaxAbsVoltage_V || std::abs(y[k]) > kFitMaxAbsPosition_m) {
      const bool bad_u = std::abs(u[k]) > kFitMaxAbsVoltage_V;
      const char* const unit = bad_u ? "V" : "m";
      return FitCheck{
          FitStatus::out_of_range,
          fmt::format("sample {}: {} = {:g} {} is beyond the sanity bound +-{:g} {} (u in volts, y in metres?)", k,
                      bad_u ? "u" : "y", bad_u ? u[k] : y[k], unit, bad_u ? kFitMaxAbsVoltage_V : kFitMaxAbsPosition_m,
                      unit)};
    }
  }
  return {};
}

FitCheck check_fit_input(std::span<const double> u, std::span<const double> y, double min_input_range_V,
                         double* u_min_V, double* u_max_V) {
  if (FitCheck c = check_fit_samples(u, y); !c.ok()) return c;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  if (!(*hi - *lo >= min_input_range_V) || *hi == *lo) {
    return FitCheck{FitStatus::constant_input,
                    fmt::format("u spans {:g} V (< {:g} V): nothing to identify", *hi - *lo, min_input_range_V)};
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
    return FitCheck{FitStatus::solver_failure,
                    fmt::format("the fit's residual is {:g}: no usable solution", residual_rms_m)};
  }
  if (residual_rms_m > y_span_m) {
    return FitCheck{
        FitStatus::out_of_range,
        fmt::format("the fit's residual {:g} m RMS exceeds the data's span {:g} m: the model explains nothing",
                    residual_rms_m, y_span_m)};
  }
  return {};
}

FitCheck check_katalenic_params(const KatalenicParams& params, double u_span_V) {
  if (FitCheck c = check_valid(params, "Katalenic parameters outside their domain: "); !c.ok()) return c;
  if (!(params.k1 <= u_span_V)) {
    return FitCheck{FitStatus::out_of_range, fmt::format("k1 = {:g} V exceeds the input span {:g} V: a band that wide "
                                                         "never moves, so the data do not determine it",
                                                         params.k1, u_span_V)};
  }
  const double sharpness = params.k2 * u_span_V;
  if (!(sharpness >= 1e-6 && sharpness <= 1e6)) {
    return FitCheck{FitStatus::out_of_range,
                    fmt::format("k2 = {:g} 1/V times the input span {:g} V is {:g} (outside [1e-6, 1e6]): the "
                                "transition cannot be told from a line or a corner",
                                params.k2, u_span_V, sharpness)};
  }
  return {};
}

}  // namespace hystloop
