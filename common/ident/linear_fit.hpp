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

LinearFitResult fit_linear(std::span<const double> u_V, std::span<const double> y_m, double min_input_range_V = 1e-3);

}  // namespace hystloop
