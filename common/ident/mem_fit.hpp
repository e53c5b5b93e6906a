#pragma once
// Identification of the MEM hysteresis model (Strijbosch, Tiels & Oomen, Section III) by
// separable (variable-projection) least squares: for a given c3 the parameters that enter
// linearly are solved in closed form (Theorem 5, eqs. (12)-(17)), the projected residual is
// minimised over the single nonlinear c3 by a grid + Brent search, and (c1, c2, c3) are finally
// refined jointly by Ceres with a robust loss.
//
// Two forms of the data:
//   derivative  (paper):  z_k = dy/du over the sample interval against p, kept only where the
//               signal-to-noise ratio |du| * slope / (sqrt(2) sigma_y) reaches min_snr; the model
//               of z_k is the exact mean of M(p) = c1 + c2 p^c3 over [p_{k-lag}, p_k], so
//               noise-free data are fitted without a discretisation bias.
//   integrated: y_k - y_b = s_b (c1 p + c2 p^(c3+1) / (c3+1)) on branch b with direction s_b;
//               the branch start y_b is a free (linear) offset per branch, so the noise on the
//               one sample at the reversal does not bias the fit. Much less noise-sensitive.
// Units: u [V], y [m], c1 [m/V], c2 [m/V^(1+c3)], c3 [-].

#include <cstddef>
#include <span>
#include <string>

#include "ident/branches.hpp"
#include "ident/fit_clock.hpp"
#include "ident/fit_status.hpp"
#include "models/mem.hpp"

namespace hystloop {

enum class MemFitForm { integrated, derivative };
enum class RobustLoss { none, huber, cauchy };

struct MemFitOptions {
  MemFitForm form = MemFitForm::integrated;
  double c3_min = 0.05;      // search interval of the nonlinear parameter
  double c3_max = 5.0;       // also the physical upper limit: an optimum at it is refused
  int c3_grid_points = 12;   // coarse log grid that brackets the global minimum
  int brent_bits = 30;       // Brent precision in bits on the bracket
  double min_snr = 3.0;      // derivative form: keep points with SNR >= this
  int derivative_lag = 1;    // derivative form: difference over this many samples
  double noise_rms_m = 0.0;  // sensor noise; 0 = estimate from the data (third difference)
  double reversal_dead_band_V = 0.0;
  std::size_t min_branches = 2;     // complete branches after the first reversal
  std::size_t min_samples = 50;     // usable samples (points, in the derivative form)
  double min_input_range_V = 1e-3;  // below this u is "constant"
  // c1 (the slope right after a reversal) >= this x the data's mean slope. A MEM element
  // fitted to a stage whose slope saturates (Coleman-Hodgdon) otherwise drifts to c1 -> 0,
  // c3 -> 0, and its inverse would jump the voltage at every reversal. 0 = only c1 >= 0.
  double min_c1_fraction = 0.25;
  RobustLoss robust_loss = RobustLoss::huber;
  double robust_scale_sigmas = 1.345;  // loss scale in robust sigmas of the projected residual
  bool refine_with_ceres = true;
  double max_solver_time_s = 0.05;  // refinement budget, read from `clock` between rounds
  int max_solver_iterations = 50;
  FitClock clock{};  // empty = monotonic; fixed_fit_clock() for a reproducible fit

  // Throws ParameterError naming the field.
  void validate() const;
};

// residual_rms_m: the integrated-branch residual (per-branch offsets fitted), in both forms;
// samples_used: samples (integrated) or difference points (derivative).
struct MemFitResult : FitOutcome {
  MemParams params{};
  std::size_t branches_used = 0;
  // The best MEM element lies on the domain's edge (c1 at its floor, or c2 = 0): the data are
  // not exactly MEM-shaped. The parameters are usable; expect a larger model error.
  bool constrained = false;
  double noise_rms_m = 0.0;   // noise level used (given or estimated)
  double projected_c3 = 0.0;  // c3 from the variable-projection search, before Ceres
};

// Fits (c1, c2, c3) to the samples. Never throws for bad data: the status says why it refused;
// throws ParameterError only for invalid options.
MemFitResult fit_mem(std::span<const double> u_V, std::span<const double> y_m, const MemFitOptions& options = {});

// RMS [m] of y - (y_b + s_b * params.branch_rise(|u - u_b|)) over the given branches, with y_b the least-squares
// offset of each branch: how well the parameters explain the branch shapes.
double mem_branch_rms(std::span<const double> u_V, std::span<const double> y_m, std::span<const BranchSegment> branches,
                      const MemParams& params);

}  // namespace hystloop
