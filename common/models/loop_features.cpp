#include "models/loop_features.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {

void LoopFeatureOptions::validate() const {
  require_in_range("branch_degree", branch_degree, 1.0, 16.0);
  require_positive("reversal_fraction", reversal_fraction);
  require_in_range("reversal_fraction", reversal_fraction, 0.0, 0.5);
}

std::string_view describe(LoopFeatureStatus status) noexcept {
  switch (status) {
    case LoopFeatureStatus::kOk: return "ok";
    case LoopFeatureStatus::kNonFinite: return "a sample is not finite";
    case LoopFeatureStatus::kNoExcursion: return "the input does not move";
    case LoopFeatureStatus::kIncompleteLoop: return "a branch does not cover the input span (less than one period)";
    case LoopFeatureStatus::kTooFewSamples: return "too few samples on a branch for the fit degree";
    case LoopFeatureStatus::kNoCrossing: return "a branch does not cross the centre level";
  }
  return "unknown";
}

namespace {

// A fitted branch y(x) = sum c_n T_n(x), x in [-1, 1].
struct Branch {
  std::vector<double> x;
  std::vector<double> y;
  Eigen::VectorXd coef;

  double operator()(double t) const noexcept {  // Clenshaw recurrence
    double b1 = 0.0;
    double b2 = 0.0;
    for (Eigen::Index n = coef.size() - 1; n >= 1; --n) {
      const double b0 = 2.0 * t * b1 - b2 + coef(n);
      b2 = b1;
      b1 = b0;
    }
    return t * b1 - b2 + coef(0);
  }

  double integral() const noexcept {  // over [-1, 1]: int T_n = 2 / (1 - n^2) for even n
    double s = 0.0;
    for (Eigen::Index n = 0; n < coef.size(); n += 2) {
      const double nd = static_cast<double>(n);
      s += coef(n) * 2.0 / (1.0 - nd * nd);
    }
    return s;
  }

  // Least squares through a column-pivoting QR; returns the sum of squared residuals.
  double fit(int degree) {
    const auto rows = static_cast<Eigen::Index>(x.size());
    const Eigen::Index cols = degree + 1;
    Eigen::MatrixXd m(rows, cols);
    Eigen::VectorXd rhs(rows);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const double t = x[static_cast<std::size_t>(i)];
      m(i, 0) = 1.0;
      if (cols > 1) m(i, 1) = t;
      for (Eigen::Index n = 2; n < cols; ++n) m(i, n) = 2.0 * t * m(i, n - 1) - m(i, n - 2);
      rhs(i) = y[static_cast<std::size_t>(i)];
    }
    coef = m.colPivHouseholderQr().solve(rhs);
    return (m * coef - rhs).squaredNorm();
  }

  bool covers(double tol) const noexcept {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    return *lo <= -1.0 + tol && *hi >= 1.0 - tol;
  }

  // x in [-1, 1] where the branch equals level; NaN when the end values do not bracket it.
  double crossing(double level) const noexcept {
    double lo = -1.0;
    double hi = 1.0;
    double flo = (*this)(lo)-level;
    if (flo * ((*this)(hi)-level) > 0.0) return std::nan("");
    for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
      const double mid = 0.5 * (lo + hi);
      const double fmid = (*this)(mid)-level;
      if ((fmid < 0.0) == (flo < 0.0)) {
        lo = mid;
        flo = fmid;
      } else {
        hi = mid;
      }
    }
    return 0.5 * (lo + hi);
  }
};

// Indices where u reverses, confirmed by a retreat of more than `threshold`; the extremes at
// either end of the data (confirmed or not) are included so every sample lies between two
// boundaries of one direction.
std::vector<std::size_t> reversal_boundaries(std::span<const double> u, double threshold, std::size_t& confirmed) {
  std::vector<std::size_t> b{0};
  confirmed = 0;
  int dir = 0;
  std::size_t lo = 0;
  std::size_t hi = 0;
  std::size_t cand = 0;
  for (std::size_t i = 1; i < u.size(); ++i) {
    if (dir == 0) {
      if (u[i] > u[hi]) hi = i;
      if (u[i] < u[lo]) lo = i;
      if (u[hi] - u[lo] > threshold) {
        dir = hi > lo ? 1 : -1;
        const std::size_t first = hi > lo ? lo : hi;  // the extreme before the first big move
        if (first > 0) b.push_back(first);
        cand = hi > lo ? hi : lo;
      }
    } else if ((u[i] - u[cand]) * dir >= 0.0) {
      cand = i;
    } else if ((u[cand] - u[i]) * dir > threshold) {
      b.push_back(cand);
      ++confirmed;
      dir = -dir;
      cand = i;
    }
  }
  if (dir != 0 && cand > b.back() && cand + 1 < u.size()) b.push_back(cand);
  if (b.back() != u.size() - 1) b.push_back(u.size() - 1);
  return b;
}

}  // namespace

LoopFeatureResult extract_loop_features(std::span<const double> u, std::span<const double> y,
                                        const LoopFeatureOptions& options) {
  options.validate();
  if (u.size() != y.size()) {
    throw ParameterError(
        "y", "must have as many samples as u (" + std::to_string(u.size()) + "), got " + std::to_string(y.size()));
  }
  LoopFeatureResult r;
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (!std::isfinite(u[i]) || !std::isfinite(y[i])) {
      r.status = LoopFeatureStatus::kNonFinite;
      return r;
    }
  }
  if (u.size() < 2) {
    r.status = LoopFeatureStatus::kNoExcursion;
    return r;
  }
  const auto [it_lo, it_hi] = std::minmax_element(u.begin(), u.end());
  const double u_min = *it_lo;
  const double u_max = *it_hi;
  if (!(u_max > u_min)) {
    r.status = LoopFeatureStatus::kNoExcursion;
    return r;
  }
  const double u_c = 0.5 * (u_min + u_max);
  const double half = 0.5 * (u_max - u_min);

  const std::vector<std::size_t> b = reversal_boundaries(u, options.reversal_fraction * 2.0 * half, r.reversals);
  Branch up;
  Branch down;
  for (std::size_t j = 0; j + 1 < b.size(); ++j) {
    const double rise = u[b[j + 1]] - u[b[j]];
    if (rise == 0.0) continue;
    Branch& br = rise > 0.0 ? up : down;
    for (std::size_t i = b[j]; i <= b[j + 1]; ++i) {
      br.x.push_back((u[i] - u_c) / half);
      br.y.push_back(y[i]);
    }
  }
  r.samples_ascending = up.x.size();
  r.samples_descending = down.x.size();
  if (up.x.empty() || down.x.empty() || !up.covers(0.01) || !down.covers(0.01)) {
    r.status = LoopFeatureStatus::kIncompleteLoop;
    return r;
  }
  const std::size_t need = 3u * static_cast<std::size_t>(options.branch_degree + 1);
  if (up.x.size() < need || down.x.size() < need) {
    r.status = LoopFeatureStatus::kTooFewSamples;
    return r;
  }
  const double sse = up.fit(options.branch_degree) + down.fit(options.branch_degree);
  r.residual_rms = std::sqrt(sse / static_cast<double>(up.x.size() + down.x.size()));

  LoopFeatures& f = r.features;
  f.u_min = u_min;
  f.u_max = u_max;
  f.y_left = 0.5 * (up(-1.0) + down(-1.0));
  f.y_right = 0.5 * (up(1.0) + down(1.0));
  f.u_centre = u_c;
  f.y_centre = 0.5 * (f.y_left + f.y_right);
  f.slope = (f.y_right - f.y_left) / (u_max - u_min);
  f.eta = down(0.0) - up(0.0);
  f.area = half * (down.integral() - up.integral());
  const double x_up = up.crossing(f.y_centre);
  const double x_down = down.crossing(f.y_centre);
  if (!std::isfinite(x_up) || !std::isfinite(x_down)) {
    r.status = LoopFeatureStatus::kNoCrossing;
    return r;
  }
  f.delta = half * (x_up - x_down);
  return r;
}

}  // namespace hystloop
