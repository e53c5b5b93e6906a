#pragma once
// Fit every model on the first part of a record and rank them by how well they predict the
// rest (held-out branches). Each model is simulated over the whole record from its own initial
// state: MEM from the first reversal with the measured output there (the paper's "after its
// first branching point"), PI with every play centred on u[0], Katalenic from its reset at u[0].
// A constant offset, estimated on the training part (after its second reversal), is removed
// before scoring, so a model is judged on the shape it predicts, not on where y started.

#include <array>
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

// The models identification fits (fit_candidate), in ranking order: a model the loop runs may be
// fitted elsewhere.
inline constexpr std::array kFittedModels{ModelKind::mem, ModelKind::pi, ModelKind::katalenic, ModelKind::linear};
bool has_fitter(ModelKind kind) noexcept;

struct ModelSelectionOptions {
  double holdout_fraction = 0.3;  // the held-out part starts at the first reversal after 1 - this
  std::vector<ModelKind> candidates{kFittedModels.begin(), kFittedModels.end()};
  MemFitOptions mem{};
  PiFitOptions pi{};
  KatalenicFitOptions katalenic{};
  void validate() const;  // throws ParameterError naming the field
};

struct ModelScore {
  ModelKind kind = ModelKind::mem;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  double train_rms_m = 0.0;      // fit residual as the fitter reports it
  double holdout_rms_m = 0.0;    // prediction error on the held-out part
  double fit_time_s = 0.0;       // the fitter's solve_time_s (its options' clock); linear: 0, closed form
  std::size_t samples_used = 0;  // as the fitter counts them
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

// One model fitted on all of (u, y) with its options from `options` (which validates only that
// model's), the result stored in its member of `sel` (sel.mem, sel.pi, ...). The score is the
// fitter's status, reason, residual, sample count and time; holdout_rms_m stays 0.
ModelScore fit_candidate(ModelKind kind, std::span<const double> u_V, std::span<const double> y_m,
                         const ModelSelectionOptions& options, ModelSelection& sel);

// `base` with kind and the parameters of `sel`'s fit of `kind` (the other members and the stage
// as in base). Throws ParameterError when the fit makes no valid parameter struct (PI: w_0 = 0).
ModelParamSet fitted_set(const ModelSelection& sel, ModelKind kind, ModelParamSet base = {});

// What `sel`'s fit of `kind` predicts for every u sample, as select_model scores it.
std::vector<double> fitted_prediction(const ModelSelection& sel, ModelKind kind, std::span<const double> u_V,
                                      std::span<const double> y_m);

// MEM's simulation for the scores, y [m] for every u sample (PI's and Katalenic's are beside their fits).
std::vector<double> predict_mem(const MemParams& params, std::span<const double> u_V, std::span<const double> y_m);
// The score: RMS of y - pred over [split, end) after removing their mean difference over
// [train_begin, split) (select_model uses train_begin = the second reversal, split = split_index).
double holdout_rms(std::span<const double> y_m, const std::vector<double>& pred, std::size_t train_begin,
                   std::size_t split);

}  // namespace hystloop
