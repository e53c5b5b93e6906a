#pragma once
// Baseline: y = gain u + offset by least squares (the paper's "linear spring" feedforward).

#include <cstddef>
#include <span>
#include <string>

#include "ident/fit_status.hpp"
#include "models/linear.hpp"

namespace hystloop {

struct LinearFitResult : FitOutcome {
  double gain_m_per_V = 0.0;
  double offset_m = 0.0;
};

LinearParams to_linear_params(const LinearFitResult& fit);  // validates

// y = slope x + offset by least squares, from centred sums (positions of ~1e-6 m square to ~1e-12
// m^2 without cancellation): the linear baseline's fit and the coupling fit's slopes. x must vary;
// the slope's standard error needs 3 or more samples (NaN with 2).
struct LeastSquaresLine {
  double slope = 0.0;
  double offset = 0.0;
  double residual_rms = 0.0;          // of y about the line
  double slope_standard_error = 0.0;  // sqrt(ss / (n - 2) / sxx): independent residuals of equal variance
};
LeastSquaresLine least_squares_line(std::span<const double> x, std::span<const double> y) noexcept;

LinearFitResult fit_linear(std::span<const double> u_V, std::span<const double> y_m, double min_input_range_V = 1e-3);

}  // namespace hystloop
