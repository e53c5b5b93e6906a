#include "ident/fit_checks.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace hystloop {
namespace {

FitCheck refused(FitStatus status, std::string reason) { return {status, std::move(reason)}; }

}  // namespace

FitCheck check_fit_samples(std::span<const double> u, std::span<const double> y) {
  if (u.size() != y.size() || u.empty()) {
    std::ostringstream s;
    s << "u has " << u.size() << " samples, y has " << y.size();
    return refused(FitStatus::size_mismatch, s.str());
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (!std::isfinite(u[k]) || !std::isfinite(y[k])) {
      std::ostringstream s;
      s << "sample " << k << " is not finite (u = " << u[k] << ", y = " << y[k] << ")";
      return refused(FitStatus::non_finite_data, s.str());
    }
    if (std::abs(u[k]) > kFitMaxAbsVoltage_V || std::abs(y[k]) > kFitMaxAbsPosition_m) {
      const bool bad_u = std::abs(u[k]) > kFitMaxAbsVoltage_V;
      std::ostringstream s;
      s << "sample " << k << ": " << (bad_u ? "u = " : "y = ") << (bad_u ? u[k] : y[k]) << (bad_u ? " V" : " m")
        << " is beyond the sanity bound +-" << (bad_u ? kFitMaxAbsVoltage_V : kFitMaxAbsPosition_m)
        << (bad_u ? " V" : " m") << " (u in volts, y in metres?)";
      return refused(FitStatus::out_of_range, s.str());
    }
  }
  return {};
}

FitCheck check_fit_residual(double residual_rms_m, double y_span_m) {
  if (!std::isfinite(residual_rms_m) || residual_rms_m < 0.0) {
    std::ostringstream s;
    s << "the fit's residual is " << residual_rms_m << ": no usable solution";
    return refused(FitStatus::solver_failure, s.str());
  }
  if (residual_rms_m > y_span_m) {
    std::ostringstream s;
    s << "the fit's residual " << residual_rms_m << " m RMS exceeds the data's span " << y_span_m
      << " m: the model explains nothing";
    return refused(FitStatus::out_of_range, s.str());
  }
  return {};
}

FitCheck check_mem_params(const MemParams& params) {
  try {
    params.validate();
  } catch (const ParameterError& e) {
    return refused(FitStatus::out_of_range, std::string("MEM parameters outside their domain: ") + e.what());
  }
  return {};
}

FitCheck check_katalenic_params(const KatalenicParams& params, double u_span_V) {
  try {
    params.validate();
  } catch (const ParameterError& e) {
    return refused(FitStatus::out_of_range, std::string("Katalenic parameters outside their domain: ") + e.what());
  }
  std::ostringstream s;
  if (!(params.k1 <= u_span_V)) {
    s << "k1 = " << params.k1 << " V exceeds the input span " << u_span_V
      << " V: a band that wide never moves, so the data do not determine it";
    return refused(FitStatus::out_of_range, s.str());
  }
  const double sharpness = params.k2 * u_span_V;
  if (!(sharpness >= 1e-6 && sharpness <= 1e6)) {
    s << "k2 = " << params.k2 << " 1/V times the input span " << u_span_V << " V is " << sharpness
      << " (outside [1e-6, 1e6]): the transition cannot be told from a line or a corner";
    return refused(FitStatus::out_of_range, s.str());
  }
  return {};
}

}  // namespace hystloop
