#pragma once
// Baseline: Prandtl-Ishlinskii weights by non-negative least squares (nnls.hpp). N play
// operators on evenly spaced thresholds r_i = i R / N (i = 0..N-1, R = half the input span;
// r_0 = 0 is the linear term), y = offset + sum_i w_i F_{r_i}[u] with w_i >= 0, so the fitted
// model is monotone and invertible. Only samples after the second reversal are scored: by then
// every play with r_i <= R has been wiped out and no longer depends on its initial state.

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ident/fit_clock.hpp"
#include "ident/fit_status.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

struct PiFitOptions {
  std::size_t operators = 15;  // the paper's comparison used 15 play operators; <= kPiMaxOperators
  double min_input_range_V = 1e-3;
  std::size_t min_samples = 50;
  FitClock clock{};       // solve_time_s only (NNLS has no time budget); empty = monotonic
  void validate() const;  // throws ParameterError naming the field
};

struct PiFitResult : FitOutcome {
  std::vector<double> thresholds_V;  // r_i [V]
  std::vector<double> weights;       // w_i [m/V], >= 0
  double offset_m = 0.0;
};

PiFitResult fit_pi(std::span<const double> u_V, std::span<const double> y_m, const PiFitOptions& options = {});

// Play (backlash) operator of threshold r: out_k = max(u_k - r, min(u_k + r, out_{k-1})), with
// out_{-1} = initial. Writes u.size() values.
void play_operator(std::span<const double> u_V, double r_V, double initial, std::span<double> out);

// The project's parameter set (models/prandtl_ishlinskii.hpp); the offset has no place there
// (PiModel starts demagnetised at 0) and stays in the fit result. Throws ParameterError if the
// weights do not make a valid PiParams (e.g. w_0 = 0).
PiParams to_pi_params(const PiFitResult& fit);

// y predicted by fitted PI weights, every play started at initial = u[0] (centred state).
std::vector<double> predict_pi(const PiFitResult& fit, std::span<const double> u_V);

}  // namespace hystloop
