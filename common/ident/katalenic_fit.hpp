#pragma once
// Baseline: the Katalenic smooth parametric operator fitted to (u, y) data. Variable projection
// again: for given (k1, k2) the operator output z = H(k1, k2)[u] (input shaping the identity, so
// operator units are volts) is simulated once, and the output shaping psi_out(z) — linear
// (gain, offset) or a polynomial of chosen degree — is linear in its coefficients, so it is
// solved by least squares. Ceres minimises the projected residual over (ln k1, ln k2) (central
// numeric differences: the operator is simulated, not differentiated), started from the best
// point of a small grid. Samples before the second reversal are not scored: they carry the
// unknown initial state.

#include <span>
#include <string>
#include <vector>

#include "ident/fit_clock.hpp"
#include "ident/fit_status.hpp"
#include "models/katalenic.hpp"

namespace hystloop {

struct KatalenicFitOptions {
  int output_polynomial_degree = 1;  // 1: linear shaping; 2..7: polynomial psi_out(z)
  double min_input_range_V = 1e-3;
  std::size_t min_samples = 50;
  double max_solver_time_s = 2.0;  // Ceres' budget, read from `clock`
  int max_solver_iterations = 50;
  FitClock clock{};       // empty = monotonic; fixed_fit_clock() for a reproducible fit
  void validate() const;  // throws ParameterError naming the field
};

struct KatalenicFitResult : FitOutcome {
  KatalenicParams params{};
};

KatalenicFitResult fit_katalenic(std::span<const double> u_V, std::span<const double> y_m,
                                 const KatalenicFitOptions& options = {});

// y [m] the operator with `params` gives for u, reset at u[0] (as the fit simulates it).
std::vector<double> predict_katalenic(const KatalenicParams& params, std::span<const double> u_V);

}  // namespace hystloop
