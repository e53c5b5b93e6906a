#pragma once
// The axes' coupling matrix C (models/axis_coupling.hpp) from one-axis-at-a-time experiments.
//
// Each experiment moves one axis i and holds the others still (their commands constant), and
// records every axis's sensor. With y = C s, the held axes' s_k constant and C_ii = 1:
//
//   y_i = s_i + const,   y_j = C_ji s_i + const,   so   y_j = C_ji y_i + const.
//
// C_ji is therefore the least-squares slope of y_j on y_i with an offset; the excited axis's own
// sensor stands in for its displacement, which is hysteretic and not known from its command. The
// estimate needs no model of any axis: the slope is the same on every branch of its loop.
//
// Accuracy: with independent sensor noise sigma on every sample, a slope's standard error is
// sigma / sqrt(sum (y_i - mean)^2): 1 nm on a +-0.5 um triangle of 4000 samples gives 5.5e-5.
// Correlated (filtered) noise makes the reported standard error optimistic. The noise on y_i
// itself biases every slope towards 0 by sigma^2 / var(y_i) of its value (errors in variables):
// 1.2e-5 of it on that triangle, 4.8e-3 on a 50 nm (the minimum travel) triangle: 1.4e-4 of a 3 %
// coupling, below that triangle's standard error (1.1e-3 at 4000 samples).
//
// An axis that no experiment excites: by default the fit is refused (its effect on the others,
// column i of C, is unknown). With allow_unexcited_axes its column is taken as uncoupled (0, the
// identity's) and its standard errors are NaN ("assumed, not measured"); its row -- what the
// excited axes do to it -- is still fitted, since every experiment records every axis.

#include <array>
#include <cstddef>
#include <span>

#include "ident/fit_status.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

// One experiment: `axis` moved, the others held still.
struct AxisExcitation {
  int axis = 0;  // the axis moved: 0 x, 1 y, 2 z
  // [m] every axis's sensor, sample by sample, all of one length: y_m[j] for j < the fit's axes;
  // the entries beyond them stay empty.
  std::array<std::span<const double>, kMaxAxes> y_m{};
};

struct CouplingFitOptions {
  int axes = kMaxAxes;  // n, 1..kMaxAxes
  // The excited axis's sensor must span this much peak to peak: the slopes' standard error and
  // their errors-in-variables bias grow as 1 / travel; 50 nm is 50x a 1 nm sensor's noise.
  double min_travel_m = 50e-9;
  std::size_t min_samples = 100;      // per experiment; >= 3 (a line and its residual)
  bool allow_unexcited_axes = false;  // see above: an unexcited axis's column taken as 0
  void validate() const;              // throws ParameterError naming the field
};

struct CouplingFitResult : FitOutcome {
  // The fitted C when ok; identity(n) when refused (nothing half-fitted to be used by mistake).
  AxisCoupling coupling;
  // The slopes as computed, also when refused (e.g. to show a 60 % entry AxisCoupling refused).
  // Diagonal 1; entries beyond n the identity's.
  AxisMatrix estimate = AxisMatrix::Identity();
  // Standard error of each C_ji [-]: 0 on the diagonal (1 by definition) and beyond n; NaN for the
  // column of an unexcited axis (assumed 0, not measured).
  AxisMatrix standard_error = AxisMatrix::Zero();
  // [m] RMS residual of y_j about its line on y_i, entry (j, i); NaN where not fitted.
  // FitOutcome::residual_rms_m is the largest of them.
  AxisMatrix line_residual_rms_m = AxisMatrix::Zero();
  std::array<bool, kMaxAxes> excited{};  // which axes an experiment moved
  // samples_used (FitOutcome): all experiments' samples; solve_time_s stays 0 (closed form).
};

// Refusals (status, and a reason naming the axis): an experiment's axis outside 0..n-1
// (out_of_range); an axis excited twice (size_mismatch); an axis excited by none unless allowed,
// or no experiment (too_few_samples); spans of different lengths, or non-empty beyond n
// (size_mismatch); fewer than min_samples (too_few_samples); non-finite samples (non_finite_data);
// a sample beyond the sanity bound kFitMaxAbsPosition_m (out_of_range); the excited axis spanning
// less than min_travel_m (constant_input); a fitted C that AxisCoupling refuses (out_of_range).
// Invalid options throw ParameterError.
CouplingFitResult fit_coupling(std::span<const AxisExcitation> experiments, const CouplingFitOptions& options = {});

}  // namespace hystloop
