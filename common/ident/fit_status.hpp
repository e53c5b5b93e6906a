#pragma once
// Why a fit was refused. Every fitter in common/ident returns one of these with a sentence in
// `reason`; only `ok` means the parameters may be used. Options a fitter cannot run with are not
// a status: their validate() throws ParameterError where they enter, before any data is looked at.

#include <cstddef>
#include <string>
#include <string_view>

namespace hystloop {

enum class FitStatus {
  ok,
  size_mismatch,     // u and y (or t) spans of different length, or empty
  non_finite_data,   // NaN / Inf in the samples
  constant_input,    // u spans less than the minimum input range
  too_few_branches,  // fewer complete branches (after the first reversal) than required
  too_few_samples,   // too few usable samples (e.g. all below the SNR threshold)
  out_of_range,      // samples beyond the sanity bounds, or the optimum outside the model's domain
  solver_failure,    // the nonlinear solver did not return a usable solution
  no_improvement,    // (online) valid, but does not predict held-out data better than the set in use
  poisoned_window,   // (online) the window holds dropped / stuck / non-finite samples
};

std::string_view to_string(FitStatus status) noexcept;

// What the result of each model's fit (MEM, PI, Katalenic, linear) holds beside its parameters.
struct FitOutcome {
  double residual_rms_m = 0.0;  // [m] on the samples scored
  std::size_t samples_used = 0;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  double solve_time_s = 0.0;  // the fit's time by its options' clock (instrumentation only); linear: 0
  bool ok() const noexcept { return status == FitStatus::ok; }
};

}  // namespace hystloop
