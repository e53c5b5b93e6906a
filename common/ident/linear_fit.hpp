#pragma once
// Baseline: y = gain u + offset by least squares (the paper's "linear spring" feedforward).

#include <cstddef>
#include <span>
#include <string>

#include "ident/fit_status.hpp"
#include "models/linear.hpp"

namespace hystloop {

struct LinearFitResult {
  double gain_m_per_V = 0.0;
  double offset_m = 0.0;
  double residual_rms_m = 0.0;
  std::size_t samples_used = 0;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  bool ok() const noexcept { return status == FitStatus::ok; }
};

LinearParams to_linear_params(const LinearFitResult& fit);  // validates

LinearFitResult fit_linear(std::span<const double> u_V, std::span<const double> y_m, double min_input_range_V = 1e-3);

}  // namespace hystloop
