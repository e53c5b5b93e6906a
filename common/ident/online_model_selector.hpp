#pragma once
// The online model choice (the re-identifier's second core, beside OnlineMemEstimator): from the
// estimator's window of recent (u, y), fit every candidate model (select_model: MEM, PI-15,
// Katalenic, linear; no fitting code of its own), rank them on the held-out branches at the end
// of the window, score the parameter set IN USE on the same held-out samples, and propose
//
//   * a change of model when the best candidate beats the model in use by `margin` (relative),
//     both as it runs (the set in use) and as refitted on this window: a near tie keeps the model
//     in use, so two models of similar quality never alternate;
//   * otherwise new parameters of the model in use when its refit beats the set in use by
//     `refit_improvement` (the same rule as OnlineMemEstimator's min_relative_improvement);
//   * otherwise nothing.
// A candidate is proposed only if it predicts the held-out part about as well as it fits the
// rest (max_holdout_to_train): a window that holds a change of regime is not trusted.
//
// With `pinned` the model never changes; its parameters are still refitted. A proposal is always
// a set that ModelParamSet::validate() accepts (it is validated here before it is returned), so a
// published proposal is never one the compensator refuses.
//
// propose_model() is a pure function of its arguments: run it on any thread. It allocates and
// takes as long as the fits do (seconds on a 4 s window at 10 kHz; `decimation` divides that).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ident/fit_status.hpp"
#include "ident/model_selection.hpp"
#include "models/model_set.hpp"

namespace hystloop {

struct OnlineSelectorOptions {
  // Relative margin a different model must win by (0.10: its held-out RMS <= 0.90 x the model in
  // use's). docs/TRACKING.md, "Choosing the model online", gives the measurements behind it.
  double margin = 0.10;
  // Relative improvement a refit of the model in use must reach to be proposed.
  double refit_improvement = 0.02;
  // A candidate whose held-out RMS exceeds this multiple of its own fit residual was fitted to a
  // window that changed under it (a swap's transient, the loop moving): it is not proposed.
  double max_holdout_to_train = 2.0;
  bool pinned = false;         // never propose a different model (parameters are still refitted)
  std::size_t decimation = 1;  // fit every n-th sample of the window, and its extremes (>= 1; 10 kHz / 10 = 1 kHz)
  ModelSelectionOptions selection{};  // candidates, held-out fraction, fitter options

  void validate() const;  // throws ParameterError naming the field
};

enum class ProposalKind : std::uint8_t {
  none,          // keep what is in use (reason says why)
  refit,         // new parameters of the model in use
  model_change,  // a different model (never with pinned)
};

std::string_view to_string(ProposalKind kind) noexcept;

struct ModelProposal {
  ProposalKind kind = ProposalKind::none;
  ModelParamSet params{};                        // the proposal (meaningful unless kind == none); validated
  FitStatus status = FitStatus::solver_failure;  // of the selection (ok: at least one model fitted)
  std::string reason;                            // why this decision, with the figures
  ModelKind in_use = ModelKind::mem;
  ModelKind winner = ModelKind::mem;        // best refitted candidate
  double in_use_holdout_rms_m = 0.0;        // the set in use on the held-out samples
  double in_use_refit_holdout_rms_m = 0.0;  // the in-use kind refitted on this window (inf: not fitted)
  double winner_holdout_rms_m = 0.0;
  std::vector<ModelScore> ranking;  // select_model's, best first
  bool proposes() const noexcept { return kind != ProposalKind::none; }
};

// u_V, y_m: the window, oldest first (OnlineMemEstimator::snapshot). in_use: the set the
// compensator runs now. Throws ParameterError for invalid options or an invalid in_use.
ModelProposal propose_model(std::span<const double> u_V, std::span<const double> y_m, const ModelParamSet& in_use,
                            const OnlineSelectorOptions& options = {});

// The samples a decimated fit keeps: every n-th, and inside each block of n the sample where u
// is largest or smallest when it passes the block's ends by more than 0.1 V (a reversal, not the
// servo's tick-to-tick noise). Hysteresis is
// rate-independent, so the models need u's turning points, not an even clock: every 10th
// sample of a 100 Hz line misses its peaks by up to 5 % of the amplitude, and a play operator
// fed the missed peak starts its next branch in the wrong place (fitted PI sets then had their
// slope steps where the stage's were not, which rang the 1.72 kHz resonance at 10 nm). Between
// two kept samples u is monotone up to what turns inside a block twice. Indices increasing.
std::vector<std::size_t> decimate_keeping_extremes(std::span<const double> u, std::size_t n);

// The output a parameter set predicts for u over the window, as select_model scores its
// candidates (MEM from the first reversal at the measured y, PI/Katalenic from u[0], linear).
std::vector<double> predict_model(const ModelParamSet& params, std::span<const double> u_V,
                                  std::span<const double> y_m);

}  // namespace hystloop
