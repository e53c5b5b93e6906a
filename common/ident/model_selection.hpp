#pragma once
// Fit every model on the first part of a record and rank them by how well they predict the
// rest (held-out branches). Each model is simulated over the whole record from its own initial
// state: MEM from the first reversal with the measured output there (the paper's "after its
// first branching point"), PI with every play centred on u[0], Katalenic from its reset at u[0].
// A constant offset, estimated on the training part (after its second reversal), is removed
// before scoring, so a model is judged on the shape it predicts, not on where y started.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ident/fit_status.hpp"
#include "ident/katalenic_fit.hpp"
#include "ident/linear_fit.hpp"
#include "ident/mem_fit.hpp"
#include "ident/pi_fit.hpp"
#include "models/model_set.hpp"  // ModelKind

namespace hystloop {

struct ModelSelectionOptions {
  double holdout_fraction = 0.3;  // the held-out part starts at the first reversal after 1 - this
  std::vector<ModelKind> candidates{ModelKind::mem, ModelKind::pi, ModelKind::katalenic, ModelKind::linear};
  MemFitOptions mem{};
  PiFitOptions pi{};
  KatalenicFitOptions katalenic{};
  void validate() const;  // throws ParameterError naming the field
};

struct ModelScore {
  ModelKind kind = ModelKind::mem;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  double train_rms_m = 0.0;    // fit residual as the fitter reports it
  double holdout_rms_m = 0.0;  // prediction error on the held-out part
  double fit_time_s = 0.0;     // the fitter's solve_time_s (its options' clock); linear: 0, closed form
};

struct ModelSelection {
  std::vector<ModelScore> ranking;  // best first; refused fits last
  std::size_t split_index = 0;      // first held-out sample
  MemFitResult mem;
  PiFitResult pi;
  KatalenicFitResult katalenic;
  LinearFitResult linear;
  FitStatus status = FitStatus::solver_failure;  // ok if at least one model was fitted and scored
  std::string reason;
  bool ok() const noexcept { return status == FitStatus::ok; }
};

ModelSelection select_model(std::span<const double> u_V, std::span<const double> y_m,
                            const ModelSelectionOptions& options = {});

// Simulations used for the scores (y [m] for every u sample).
std::vector<double> predict_mem(const MemParams& params, std::span<const double> u_V, std::span<const double> y_m);
std::vector<double> predict_katalenic(const KatalenicParams& params, std::span<const double> u_V);
// The score: RMS of y - pred over [split, end) after removing their mean difference over
// [train_begin, split) (select_model uses train_begin = the second reversal, split = split_index).
double holdout_rms(std::span<const double> y_m, const std::vector<double>& pred, std::size_t train_begin,
                   std::size_t split);

}  // namespace hystloop
