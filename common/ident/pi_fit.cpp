#include "ident/pi_fit.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "ident/branches.hpp"
#include "ident/fit_checks.hpp"
#include "ident/fit_clock.hpp"
#include "ident/nnls.hpp"

namespace hystloop {

void PiFitOptions::validate() const {
  if (operators < 1 || operators > kPiMaxOperators) {
    throw ParameterError("operators", "must be in [1, " + std::to_string(kPiMaxOperators) + "]");
  }
  require_non_negative("min_input_range_V", min_input_range_V);
  if (min_samples < 8) throw ParameterError("min_samples", "must be >= 8");
}

void play_operator(std::span<const double> u, double r, double initial, std::span<double> out) {
  double prev = initial;
  for (std::size_t k = 0; k < u.size(); ++k) {
    prev = std::max(u[k] - r, std::min(u[k] + r, prev));
    out[k] = prev;
  }
}

PiParams to_pi_params(const PiFitResult& fit) {
  if (fit.weights.size() > kPiMaxOperators || fit.weights.size() != fit.thresholds_V.size()) {
    throw ParameterError("count", "must be in [1, " + std::to_string(kPiMaxOperators) + "]");
  }
  PiParams p;
  p.count = fit.weights.size();
  for (std::size_t i = 0; i < p.count; ++i) p.thresholds[i] = fit.thresholds_V[i], p.weights[i] = fit.weights[i];
  p.validate();
  return p;
}

std::vector<double> predict_pi(const PiFitResult& fit, std::span<const double> u) {
  std::vector<double> y(u.size(), fit.offset_m), play(u.size());
  if (u.empty()) return y;
  for (std::size_t i = 0; i < fit.weights.size(); ++i) {
    play_operator(u, fit.thresholds_V[i], u[0], play);
    for (std::size_t k = 0; k < u.size(); ++k) y[k] += fit.weights[i] * play[k];
  }
  return y;
}

PiFitResult fit_pi(std::span<const double> u, std::span<const double> y, const PiFitOptions& o) {
  o.validate();
  const FitTimer timer(o.clock);
  PiFitResult res;
  double lo = 0.0, hi = 0.0;
  std::size_t begin = 0;
  if (FitCheck c = check_fit_input(u, y, o.min_input_range_V, &lo, &hi); !c.ok()) return timer.finish(res, c);
  if (FitCheck c = check_after_second_reversal(u, o.min_samples, &begin); !c.ok()) return timer.finish(res, c);
  const double half = 0.5 * (hi - lo);
  const auto m = static_cast<Eigen::Index>(u.size() - begin);
  res.samples_used = u.size() - begin;
  const auto n = static_cast<Eigen::Index>(o.operators);
  // Centred columns: the free offset is eliminated, the weights stay non-negative.
  Eigen::MatrixXd a(m, n);
  std::vector<double> play(u.size());
  res.thresholds_V.resize(o.operators);
  for (Eigen::Index i = 0; i < n; ++i) {
    res.thresholds_V[static_cast<std::size_t>(i)] = half * static_cast<double>(i) / static_cast<double>(n);
    play_operator(u, res.thresholds_V[static_cast<std::size_t>(i)], u[0], play);
    for (Eigen::Index k = 0; k < m; ++k) a(k, i) = play[begin + static_cast<std::size_t>(k)];
  }
  Eigen::VectorXd b(m);
  for (Eigen::Index k = 0; k < m; ++k) b[k] = y[begin + static_cast<std::size_t>(k)];
  const Eigen::RowVectorXd amean = a.colwise().mean();
  const double bmean = b.mean();
  Eigen::MatrixXd ac = a.rowwise() - amean;
  const Eigen::VectorXd bc = b.array() - bmean;
  // Scale to O(1) (volts and metres differ by 1e9) for the active-set tolerances.
  const double ys = std::max(bc.cwiseAbs().maxCoeff(), 1e-300), us = std::max(half, 1e-300);
  const NnlsResult nn = nnls(ac / us, bc / ys);
  if (!nn.converged)
    return timer.finish(res, FitStatus::solver_failure,
                        "NNLS did not converge in " + std::to_string(nn.iterations) + " iterations");
  const Eigen::VectorXd w = nn.x * (ys / us);
  res.weights.assign(w.data(), w.data() + n);
  res.offset_m = bmean - amean.dot(w);
  res.residual_rms_m = std::sqrt((bc - ac * w).squaredNorm() / static_cast<double>(m));
  if (!(w.sum() > 0.0)) return timer.finish(res, FitStatus::out_of_range, "all weights are zero: y does not follow u");
  if (FitCheck c = check_fit_residual(res.residual_rms_m, 2.0 * bc.cwiseAbs().maxCoeff()); !c.ok()) {
    return timer.finish(res, c.status, std::move(c.reason));
  }
  return timer.finish(res, FitStatus::ok, "");
}

}  // namespace hystloop
