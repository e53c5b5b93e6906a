#include "fit_curves.hpp"

#include <cmath>

#include "ident/branches.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

FitCurve curve(ModelKind kind, std::vector<double> prediction) {
  FitCurve c;
  c.kind = kind;
  c.heldout_begin = prediction.size();
  c.y_model_m = std::move(prediction);
  return c;
}

// fitted_prediction, but for MEM NaN before the first reversal: predict_mem copies the measured
// y there (the state is unknown), and a plot must not show that as the model agreeing perfectly.
std::vector<double> prediction(const ModelSelection& sel, ModelKind kind, std::span<const double> u,
                               std::span<const double> y) {
  std::vector<double> out = fitted_prediction(sel, kind, u, y);
  if (kind != ModelKind::mem) return out;
  const std::vector<std::size_t> rev = find_reversals(u);
  const std::size_t start = rev.empty() ? 0 : rev.front();
  for (std::size_t k = 0; k < start && k < out.size(); ++k) out[k] = kNaN;
  return out;
}

}  // namespace

FitCurve whole_record_curve(const ModelSelection& fit, ModelKind kind, std::span<const double> u_V,
                            std::span<const double> y_m) {
  return curve(kind, prediction(fit, kind, u_V, y_m));
}

std::vector<FitCurve> ranked_curves(const ModelSelection& sel, std::span<const double> u, std::span<const double> y) {
  std::vector<FitCurve> out;
  if (!sel.ok()) return out;
  const std::vector<std::size_t> rev = find_reversals(u);
  const std::size_t split = sel.split_index;
  const std::size_t train_begin = rev.size() > 1 ? rev[1] : 0;  // as select_model scores
  for (const ModelScore& score : sel.ranking) {
    if (score.status != FitStatus::ok) continue;
    std::vector<double> pred = prediction(sel, score.kind, u, y);
    double offset = 0.0;
    std::size_t n = 0;
    for (std::size_t k = train_begin; k < split && k < pred.size(); ++k, ++n) offset += y[k] - pred[k];
    offset = n > 0 ? offset / static_cast<double>(n) : 0.0;
    FitCurve c = curve(score.kind, std::move(pred));
    for (double& v : c.y_model_m) v += offset;  // NaN stays NaN
    c.offset_m = offset;
    c.heldout_begin = split;
    c.heldout_rms_m = score.holdout_rms_m;
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace hystloop
