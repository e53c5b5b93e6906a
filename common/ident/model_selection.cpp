#include "ident/model_selection.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <string>

#include "core/errors.hpp"
#include "ident/branches.hpp"
#include "ident/fit_clock.hpp"

namespace hystloop {

bool has_fitter(ModelKind kind) noexcept { return std::ranges::find(kFittedModels, kind) != kFittedModels.end(); }

void ModelSelectionOptions::validate() const {
  require_in_range("holdout_fraction", holdout_fraction, 0.05, 0.8);
  if (candidates.empty()) throw ParameterError("candidates", "must name at least one model");
  for (const ModelKind kind : candidates) {
    if (!has_fitter(kind)) throw ParameterError("candidates", std::string(to_string(kind)) + " has no fitter");
  }
  mem.validate();
  pi.validate();
  katalenic.validate();
}

std::vector<double> predict_mem(const MemParams& params, std::span<const double> u, std::span<const double> y) {
  std::vector<double> out(u.size(), 0.0);
  const std::vector<std::size_t> rev = find_reversals(u);
  MemModel model(params);
  std::size_t start = 0;
  if (rev.empty()) {
    model.reset_to_branch(u.empty() ? 0.0 : u[0], y.empty() ? 0.0 : y[0]);
  } else {
    start = rev.front();
    model.reset_to_branch(u[start], y[start]);
  }
  for (std::size_t k = 0; k < start; ++k) out[k] = y[k];  // before the first branching point: unknown state
  for (std::size_t k = start; k < u.size(); ++k) out[k] = model.forward(u[k]);
  return out;
}

// Held-out RMS after removing the offset estimated on [train_begin, split).
double holdout_rms(std::span<const double> y, const std::vector<double>& pred, std::size_t train_begin,
                   std::size_t split) {
  double off = 0.0;
  for (std::size_t k = train_begin; k < split; ++k) off += y[k] - pred[k];
  off /= static_cast<double>(std::max<std::size_t>(split - train_begin, 1));
  double ss = 0.0;
  for (std::size_t k = split; k < y.size(); ++k) ss += std::pow(y[k] - pred[k] - off, 2);
  return std::sqrt(ss / static_cast<double>(std::max<std::size_t>(y.size() - split, 1)));
}

namespace {

ModelScore score_of(ModelKind kind, const FitOutcome& r) {
  return {kind, r.status, r.reason, r.residual_rms_m, 0.0, r.solve_time_s, r.samples_used};
}

}  // namespace

ModelScore fit_candidate(ModelKind kind, std::span<const double> u, std::span<const double> y,
                         const ModelSelectionOptions& o, ModelSelection& sel) {
  switch (kind) {
    case ModelKind::mem: return score_of(kind, sel.mem = fit_mem(u, y, o.mem));
    case ModelKind::pi: return score_of(kind, sel.pi = fit_pi(u, y, o.pi));
    case ModelKind::katalenic: return score_of(kind, sel.katalenic = fit_katalenic(u, y, o.katalenic));
    case ModelKind::linear: return score_of(kind, sel.linear = fit_linear(u, y, o.mem.min_input_range_V));
    default: break;  // a model the loop runs but nothing here fits (options.validate() refuses it)
  }
  return {kind, FitStatus::solver_failure, std::string(to_string(kind)) + " has no fitter", 0.0, 0.0, 0.0, 0};
}

ModelParamSet fitted_set(const ModelSelection& sel, ModelKind kind, ModelParamSet base) {
  base.kind = kind;
  switch (kind) {
    case ModelKind::mem: base.mem = sel.mem.params; break;
    case ModelKind::pi: base.pi = to_pi_params(sel.pi); break;
    case ModelKind::katalenic: base.katalenic = sel.katalenic.params; break;
    case ModelKind::linear: base.linear = to_linear_params(sel.linear); break;
    default: throw ParameterError("kind", std::string(to_string(kind)) + " has no fitter");
  }
  return base;
}

std::vector<double> fitted_prediction(const ModelSelection& sel, ModelKind kind, std::span<const double> u,
                                      std::span<const double> y) {
  switch (kind) {
    case ModelKind::mem: return predict_mem(sel.mem.params, u, y);
    case ModelKind::pi: return predict_pi(sel.pi, u);
    case ModelKind::katalenic: return predict_katalenic(sel.katalenic.params, u);
    case ModelKind::linear: break;
    default: return std::vector<double>(u.size(), 0.0);  // no fitter, no fit (as fit_candidate says)
  }
  std::vector<double> pred(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) pred[k] = sel.linear.gain_m_per_V * u[k] + sel.linear.offset_m;
  return pred;
}

ModelSelection select_model(std::span<const double> u, std::span<const double> y, const ModelSelectionOptions& o) {
  o.validate();
  ModelSelection sel;
  if (u.size() != y.size() || u.empty()) {
    return with_status(std::move(sel), FitStatus::size_mismatch, "u and y differ in length or are empty");
  }
  const std::vector<std::size_t> rev = find_reversals(u);
  const auto target = static_cast<std::size_t>((1.0 - o.holdout_fraction) * static_cast<double>(u.size()));
  const auto it = std::lower_bound(rev.begin(), rev.end(), target);
  if (rev.size() < 4 || it == rev.end() || static_cast<std::size_t>(it - rev.begin()) < 3) {
    return with_status(
        std::move(sel), FitStatus::too_few_branches,
        fmt::format("{} reversals: need >= 3 before and 1 after {:g} % of the record to fit and hold out", rev.size(),
                    (1.0 - o.holdout_fraction) * 100.0));
  }
  sel.split_index = *it;
  const std::size_t split = sel.split_index, train_begin = rev[1];
  const auto ut = u.first(split + 1), yt = y.first(split + 1);
  for (ModelKind kind : o.candidates) {
    ModelScore score = fit_candidate(kind, ut, yt, o, sel);
    if (score.status == FitStatus::ok) {
      score.holdout_rms_m = holdout_rms(y, fitted_prediction(sel, kind, u, y), train_begin, split);
    }
    sel.ranking.push_back(score);
  }
  std::stable_sort(sel.ranking.begin(), sel.ranking.end(), [](const ModelScore& a, const ModelScore& b) {
    const bool ao = a.status == FitStatus::ok, bo = b.status == FitStatus::ok;
    if (ao != bo) return ao;
    return ao && a.holdout_rms_m < b.holdout_rms_m;
  });
  const FitStatus best = sel.ranking.front().status;
  const std::string why = best == FitStatus::ok ? "" : "no model could be fitted: " + sel.ranking.front().reason;
  return with_status(std::move(sel), best, why);
}

}  // namespace hystloop
