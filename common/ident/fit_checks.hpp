#pragma once
// The one home of the checks every fitter makes on its data and on its answer, so that a fit
// either is usable or says why not:
//  - data: equal lengths, finite, and within the physical sanity bounds (a voltage beyond 10 kV
//    or a position beyond 1 m is a unit mistake, and squares of 1e300 overflow to Inf/NaN);
//  - answer: a finite residual no larger than the data's own spread (a constant does that well),
//    and parameters inside the model's validated domain.
// The bounds equal kMaxAbsVoltage_V / kMaxAbsPosition_m of the message contract
// (common/lcm/message_checks.hpp); ident has no LCM, so tools/identify asserts that they agree.

#include <cstddef>
#include <span>
#include <string>

#include "core/errors.hpp"
#include "ident/fit_status.hpp"
#include "models/katalenic.hpp"
#include "models/mem.hpp"

namespace hystloop {

inline constexpr double kFitMaxAbsVoltage_V = 1.0e4;
inline constexpr double kFitMaxAbsPosition_m = 1.0;

struct FitCheck {
  FitStatus status = FitStatus::ok;
  std::string reason;
  bool ok() const noexcept { return status == FitStatus::ok; }
};

// size_mismatch (different lengths or empty), non_finite_data, or out_of_range naming the first
// bad sample ("sample 12: u = 2.5e+302 V is beyond the sanity bound +-10000 V").
FitCheck check_fit_samples(std::span<const double> u_V, std::span<const double> y_m);

// The input check every fitter makes first: check_fit_samples, then constant_input when u spans
// less than min_input_range_V (or nothing at all). Writes u's extremes to *u_min_V / *u_max_V
// when given (valid when ok).
FitCheck check_fit_input(std::span<const double> u_V, std::span<const double> y_m, double min_input_range_V,
                         double* u_min_V = nullptr, double* u_max_V = nullptr);

// For fitters that score only the samples after the second reversal of u (before it, the
// operators still carry their unknown initial state): too_few_branches with fewer than two
// reversals, too_few_samples with fewer than min_samples from there. Writes the first scored
// index to *begin (valid when ok).
FitCheck check_after_second_reversal(std::span<const double> u_V, std::size_t min_samples, std::size_t* begin);

// solver_failure if the residual is not finite or negative; out_of_range if it exceeds y_span_m.
FitCheck check_fit_residual(double residual_rms_m, double y_span_m);

// params.validate() (MemParams: finite, c1 > 0, c2 >= 0, c3 > 0; ...) as out_of_range, its
// message after `what` ("MEM parameters outside their domain: ").
template <class P>
FitCheck check_valid(const P& params, const std::string& what) {
  try {
    params.validate();
  } catch (const ParameterError& e) {
    return {FitStatus::out_of_range, what + e.what()};
  }
  return {};
}

// KatalenicParams::validate(), and the band the data can determine: 0 < k1 <= u_span_V (a wider
// backlash band never lets the operator leave its initial state), 1e-6 <= k2 u_span_V <= 1e6 (a
// transition much slower or faster than the data cannot be told from a line or a corner).
FitCheck check_katalenic_params(const KatalenicParams& params, double u_span_V);

}  // namespace hystloop
