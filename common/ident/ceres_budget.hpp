#pragma once
// Ceres' time budget read from a FitClock (ident/fit_clock.hpp) instead of Ceres' own wall
// clock, so that a fit given a fixed clock does not depend on the machine's load. Ends the solve
// as usable (USER_SUCCESS) once budget_s has passed since construction, as
// max_solver_time_in_seconds does (NO_CONVERGENCE, also usable).

#include <ceres/ceres.h>

#include "ident/fit_clock.hpp"

namespace hystloop::detail {

class CeresTimeBudget final : public ceres::IterationCallback {
 public:
  CeresTimeBudget(const FitClock& clock, double budget_s) : timer_(clock), budget_s_(budget_s) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& /*summary*/) override {
    return timer_.elapsed_s() > budget_s_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
  // Registers the callback and lifts Ceres' own wall-clock limit (this one replaces it).
  void attach(ceres::Solver::Options& options) {
    options.max_solver_time_in_seconds = 1e9;
    options.callbacks.push_back(this);
  }

 private:
  FitTimer timer_;
  double budget_s_;
};

}  // namespace hystloop::detail
