#include "ident/model_selection.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "ident/branches.hpp"

namespace hystloop {

void ModelSelectionOptions::validate() const {
  require_in_range("holdout_fraction", holdout_fraction, 0.05, 0.8);
  if (candidates.empty()) throw ParameterError("candidates", "must name at least one model");
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

std::vector<double> predict_katalenic(const KatalenicParams& params, std::span<const double> u) {
  KatalenicModel m(params);
  std::vector<double> out(u.size());
  if (u.empty()) return out;
  m.reset(u[0]);
  for (std::size_t k = 0; k < u.size(); ++k) out[k] = m.forward(u[k]);
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

ModelSelection select_model(std::span<const double> u, std::span<const double> y, const ModelSelectionOptions& o) {
  o.validate();
  ModelSelection sel;
  if (u.size() != y.size() || u.empty()) {
    sel.status = FitStatus::size_mismatch;
    sel.reason = "u and y differ in length or are empty";
    return sel;
  }
  const std::vector<std::size_t> rev = find_reversals(u);
  const auto target = static_cast<std::size_t>((1.0 - o.holdout_fraction) * static_cast<double>(u.size()));
  const auto it = std::lower_bound(rev.begin(), rev.end(), target);
  if (rev.size() < 4 || it == rev.end() || static_cast<std::size_t>(it - rev.begin()) < 3) {
    sel.status = FitStatus::too_few_branches;
    std::ostringstream s;
    s << rev.size() << " reversals: need >= 3 before and 1 after " << (1.0 - o.holdout_fraction) * 100.0
      << " % of the record to fit and hold out";
    sel.reason = s.str();
    return sel;
  }
  sel.split_index = *it;
  const std::size_t split = sel.split_index, train_begin = rev[1];
  const auto ut = u.first(split + 1), yt = y.first(split + 1);
  for (ModelKind kind : o.candidates) {
    ModelScore score;
    score.kind = kind;
    std::vector<double> pred;
    switch (kind) {
      case ModelKind::mem:
        sel.mem = fit_mem(ut, yt, o.mem);
        score.status = sel.mem.status, score.reason = sel.mem.reason, score.train_rms_m = sel.mem.residual_rms_m;
        score.fit_time_s = sel.mem.solve_time_s;
        if (sel.mem.ok()) pred = predict_mem(sel.mem.params, u, y);
        break;
      case ModelKind::pi:
        sel.pi = fit_pi(ut, yt, o.pi);
        score.status = sel.pi.status, score.reason = sel.pi.reason, score.train_rms_m = sel.pi.residual_rms_m;
        score.fit_time_s = sel.pi.solve_time_s;
        if (sel.pi.ok()) pred = predict_pi(sel.pi, u);
        break;
      case ModelKind::katalenic:
        sel.katalenic = fit_katalenic(ut, yt, o.katalenic);
        score.status = sel.katalenic.status, score.reason = sel.katalenic.reason;
        score.train_rms_m = sel.katalenic.residual_rms_m;
        score.fit_time_s = sel.katalenic.solve_time_s;
        if (sel.katalenic.ok()) pred = predict_katalenic(sel.katalenic.params, u);
        break;
      case ModelKind::linear:
        sel.linear = fit_linear(ut, yt, o.mem.min_input_range_V);
        score.status = sel.linear.status, score.reason = sel.linear.reason,
        score.train_rms_m = sel.linear.residual_rms_m;
        if (sel.linear.ok()) {
          pred.resize(u.size());
          for (std::size_t k = 0; k < u.size(); ++k) pred[k] = sel.linear.gain_m_per_V * u[k] + sel.linear.offset_m;
        }
        break;
    }
    if (!pred.empty()) score.holdout_rms_m = holdout_rms(y, pred, train_begin, split);
    sel.ranking.push_back(score);
  }
  std::stable_sort(sel.ranking.begin(), sel.ranking.end(), [](const ModelScore& a, const ModelScore& b) {
    const bool ao = a.status == FitStatus::ok, bo = b.status == FitStatus::ok;
    if (ao != bo) return ao;
    return ao && a.holdout_rms_m < b.holdout_rms_m;
  });
  if (sel.ranking.front().status == FitStatus::ok) {
    sel.status = FitStatus::ok;
  } else {
    sel.status = sel.ranking.front().status;
    sel.reason = "no model could be fitted: " + sel.ranking.front().reason;
  }
  return sel;
}

}  // namespace hystloop
