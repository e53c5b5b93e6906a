#pragma once
// Internals of fit_mem(): the joint Ceres refinement of (c1~, c2~, c3) with a robust loss,
// started from the variable-projection optimum.
//
// How, and why not one Ceres residual block per sample with a LossFunction: that costs ~70 ms
// per 20,000-sample fit in ceres::Solve's bookkeeping (measured; even one 20,000-row block costs
// ~3.5 ms per Jacobian evaluation against 0.2 ms for the arithmetic), against a 20 ms budget.
// Instead the robust loss is applied by iteratively reweighted least squares (IRLS converges to
// the same Huber/Cauchy M-estimate), and each weighted problem is solved by ceres::TinySolver
// (Levenberg-Marquardt, allocation-free after the first call) on sqrt(w_k) r_k with the branch
// offsets profiled out at their weighted least-squares values, so its Jacobian is the exact
// variable-projection one. The time bound (max_solver_time_s) is checked between reweighting
// rounds; max_solver_iterations bounds each round.

#include <string>

#include "ident/mem_fit.hpp"
#include "ident/mem_projection.hpp"

namespace hystloop::detail {

struct ScaledMem {
  double c1 = 0.0, c2 = 0.0, c3 = 0.0;  // scaled units (see mem_projection.hpp)
};

struct RefineOutcome {
  ScaledMem params;
  bool usable = false;
  std::string message;  // Ceres' summary message when not usable
  int ceres_solves = 0;
};

// The joint refinement of either form; loss_scale is in scaled residual units.
RefineOutcome refine(const IntegratedData& data, const ScaledMem& start, const MemFitOptions& options,
                     double loss_scale);
RefineOutcome refine(const DerivativeData& data, const ScaledMem& start, const MemFitOptions& options,
                     double loss_scale);

}  // namespace hystloop::detail
