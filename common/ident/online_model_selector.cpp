#include "ident/online_model_selector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "core/errors.hpp"
#include "ident/branches.hpp"

namespace hystloop {

void OnlineSelectorOptions::validate() const {
  require_in_range("margin", margin, 0.0, 0.9);
  require_in_range("refit_improvement", refit_improvement, 0.0, 0.9);
  require_in_range("max_holdout_to_train", max_holdout_to_train, 1.0, 1e6);
  if (decimation < 1 || decimation > 1000) throw ParameterError("decimation", "must be 1 to 1000");
  selection.validate();
}

std::string_view to_string(ProposalKind kind) noexcept {
  switch (kind) {
    case ProposalKind::none: return "none";
    case ProposalKind::refit: return "refit";
    case ProposalKind::model_change: return "model_change";
  }
  return "unknown";
}

std::vector<double> predict_model(const ModelParamSet& p, std::span<const double> u, std::span<const double> y) {
  switch (p.kind) {
    case ModelKind::mem: return predict_mem(p.mem, u, y);
    case ModelKind::pi: {
      PiFitResult fit;  // the parameters as a fit result, to predict as select_model does
      fit.thresholds_V.assign(p.pi.thresholds.begin(), p.pi.thresholds.begin() + static_cast<long>(p.pi.count));
      fit.weights.assign(p.pi.weights.begin(), p.pi.weights.begin() + static_cast<long>(p.pi.count));
      return predict_pi(fit, u);
    }
    default: break;
  }
  // Every other model: its forward model from a virgin state at the first sample.
  std::vector<double> out(u.size(), 0.0);
  OnlineModels::visit(p.kind, [&]<class D>() {
    typename D::Forward model(p.*D::in_set);
    if (!u.empty()) model.reset(u[0]);
    for (std::size_t k = 0; k < u.size(); ++k) out[k] = model.forward(u[k]);
  });
  return out;
}

namespace {

// The refitted set of `kind` from a selection (called for the fits that succeeded), if it makes a
// valid set.
std::optional<ModelParamSet> refitted(const ModelSelection& sel, ModelKind kind, const ModelParamSet& base) {
  try {
    ModelParamSet set = fitted_set(sel, kind, base);
    set.validate();
    return set;
  } catch (const ParameterError&) {
    return std::nullopt;
  }
}

const ModelScore* score_of(const ModelSelection& sel, ModelKind kind) {
  for (const ModelScore& s : sel.ranking) {
    if (s.kind == kind && s.status == FitStatus::ok) return &s;
  }
  return nullptr;
}

bool consistent(const ModelScore& s, const OnlineSelectorOptions& o) {
  return s.holdout_rms_m <= o.max_holdout_to_train * s.train_rms_m;
}

}  // namespace

std::vector<std::size_t> decimate_keeping_extremes(std::span<const double> u, std::size_t n) {
  // The servo's response to the sensor's noise moves u by ~0.02 V a tick: a turn that small is
  // the noise's, and keeping it would weight the fit towards the noisiest samples of each reversal.
  constexpr double kTurnTolerance_V = 0.1;
  std::vector<std::size_t> kept;
  if (u.empty()) return kept;
  n = std::max<std::size_t>(n, 1);
  kept.reserve(u.size() / n + 16);
  for (std::size_t k = 0; k < u.size(); k += n) {
    kept.push_back(k);
    const std::size_t end = std::min(k + n, u.size() - 1);  // the next kept sample (or the last)
    if (end <= k + 1) continue;
    std::size_t hi = k + 1, lo = k + 1;
    for (std::size_t i = k + 2; i < end; ++i) {
      if (u[i] > u[hi]) hi = i;
      if (u[i] < u[lo]) lo = i;
    }
    const bool above = u[hi] > std::max(u[k], u[end]) + kTurnTolerance_V;
    const bool below = u[lo] < std::min(u[k], u[end]) - kTurnTolerance_V;
    if (above && below) {
      kept.push_back(std::min(hi, lo));
      kept.push_back(std::max(hi, lo));
    } else if (above) {
      kept.push_back(hi);
    } else if (below) {
      kept.push_back(lo);
    }
  }
  if (kept.back() != u.size() - 1 && n > 1) kept.push_back(u.size() - 1);
  return kept;
}

ModelProposal propose_model(std::span<const double> u_in, std::span<const double> y_in, const ModelParamSet& in_use,
                            const OnlineSelectorOptions& o) {
  o.validate();
  in_use.validate();
  ModelProposal out;
  out.in_use = in_use.kind;
  out.winner = in_use.kind;
  std::vector<double> u, y;
  if (u_in.size() != y_in.size()) {
    out.status = FitStatus::size_mismatch;
    out.reason = "u and y differ in length";
    return out;
  }
  const std::vector<std::size_t> kept = decimate_keeping_extremes(u_in, o.decimation);
  u.reserve(kept.size());
  y.reserve(kept.size());
  for (const std::size_t k : kept) {
    u.push_back(u_in[k]);
    y.push_back(y_in[k]);
  }
  const ModelSelection sel = select_model(u, y, o.selection);
  out.status = sel.status;
  out.ranking = sel.ranking;
  if (!sel.ok()) {
    out.reason = "no selection: " + sel.reason;
    return out;
  }
  // The set in use, scored exactly as the candidates are (same split, same offset removal).
  const std::vector<std::size_t> rev = find_reversals(u);
  const std::size_t train_begin = rev.size() > 1 ? rev[1] : 0;
  out.in_use_holdout_rms_m = holdout_rms(y, predict_model(in_use, u, y), train_begin, sel.split_index);
  const ModelScore* own = score_of(sel, in_use.kind);
  const std::optional<ModelParamSet> own_refit =
      own && consistent(*own, o) ? refitted(sel, in_use.kind, in_use) : std::nullopt;
  out.in_use_refit_holdout_rms_m = own_refit ? own->holdout_rms_m : std::numeric_limits<double>::infinity();

  // The best candidate that makes a valid set (ranking is best first).
  std::optional<ModelParamSet> best;
  for (const ModelScore& s : sel.ranking) {
    if (s.status != FitStatus::ok) break;
    if (!consistent(s, o)) continue;
    if ((best = refitted(sel, s.kind, in_use))) {
      out.winner = s.kind;
      out.winner_holdout_rms_m = s.holdout_rms_m;
      break;
    }
  }
  std::ostringstream why;
  why << "held-out RMS: in use (" << to_string(in_use.kind) << ") " << out.in_use_holdout_rms_m << " m, refitted "
      << out.in_use_refit_holdout_rms_m << " m; best " << to_string(out.winner) << " " << out.winner_holdout_rms_m
      << " m";
  const double reference = std::min(out.in_use_holdout_rms_m, out.in_use_refit_holdout_rms_m);
  if (best && out.winner != in_use.kind && !o.pinned && out.winner_holdout_rms_m < (1.0 - o.margin) * reference) {
    out.kind = ProposalKind::model_change;
    out.params = *best;
    why << ": beats the model in use by more than " << o.margin * 100.0 << " %";
  } else if (own_refit && out.in_use_refit_holdout_rms_m < (1.0 - o.refit_improvement) * out.in_use_holdout_rms_m) {
    out.kind = ProposalKind::refit;
    out.params = *own_refit;
    why << (o.pinned ? " (pinned)" : "") << ": refit of the model in use, " << o.refit_improvement * 100.0
        << " % better";
  } else {
    why << (o.pinned ? " (pinned)" : "") << ": keep the set in use";
    if (!best || (own && !own_refit))
      why << " (a fit predicts the held-out part worse than " << o.max_holdout_to_train
          << "x its residual: the window changed)";
  }
  out.reason = why.str();
  return out;
}

}  // namespace hystloop
