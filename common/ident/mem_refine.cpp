#include "ident/mem_refine.hpp"

#include <ceres/tiny_solver.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace hystloop::detail {
namespace {

// Residuals d_k - o_b of the integrated form, d_k = y~_k - s_k (c1 p~ + c2 q(c3)), with o_b the
// weighted mean of d over branch b; each scaled by sqrt(w_k).
class IntegratedCost {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = 3 };
  IntegratedCost(const IntegratedData& d, const std::vector<double>& w) : d_(d), w_(w), dd_(d.y.size()) {}
  int NumResiduals() const { return static_cast<int>(d_.y.size()); }
  // Jacobian column-major (TinySolver): jac[i * N + k] = d r_k / d theta_i.
  bool operator()(const double* x, double* r, double* jac) const {
    const std::size_t n = d_.y.size();
    const double c1 = x[0], c2 = x[1], e = x[2] + 1.0;
    for (std::size_t b = 0; b < d_.groups(); ++b) {
      double sw = 0.0, sd = 0.0, sj0 = 0.0, sj1 = 0.0, sj2 = 0.0;
      for (std::size_t k = d_.group_begin[b]; k < d_.group_begin[b + 1]; ++k) {
        const double pe = pow_from_log(d_.log_p[k], e), q = pe / e, s = d_.s[k];
        Row& row = dd_[k];
        row.d = d_.y[k] - s * (c1 * d_.p[k] + c2 * q);
        row.j0 = -s * d_.p[k];
        row.j1 = -s * q;
        row.j2 = pe == 0.0 ? 0.0 : -s * c2 * pe * (d_.log_p[k] / e - 1.0 / (e * e));
        sw += w_[k], sd += w_[k] * row.d;
        sj0 += w_[k] * row.j0, sj1 += w_[k] * row.j1, sj2 += w_[k] * row.j2;
      }
      const double iw = sw > 0.0 ? 1.0 / sw : 0.0;
      for (std::size_t k = d_.group_begin[b]; k < d_.group_begin[b + 1]; ++k) {
        const double sq = std::sqrt(w_[k]);
        const Row& row = dd_[k];
        r[k] = sq * (row.d - sd * iw);
        if (jac != nullptr) {
          jac[k] = sq * (row.j0 - sj0 * iw);
          jac[n + k] = sq * (row.j1 - sj1 * iw);
          jac[2 * n + k] = sq * (row.j2 - sj2 * iw);
        }
      }
    }
    return true;
  }

 private:
  struct Row {
    double d, j0, j1, j2;
  };
  const IntegratedData& d_;
  const std::vector<double>& w_;
  mutable std::vector<Row> dd_;
};

// Derivative form: sqrt(w_k) (z~_k - c1~ - c2~ g_k(c3)).
class DerivativeCost {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = 3 };
  DerivativeCost(const DerivativeData& d, const std::vector<double>& w) : d_(d), w_(w) {}
  int NumResiduals() const { return static_cast<int>(d_.z.size()); }
  bool operator()(const double* x, double* r, double* jac) const {
    const std::size_t n = d_.z.size();
    const double c1 = x[0], c2 = x[1], c3 = x[2];
    for (std::size_t k = 0; k < d_.z.size(); ++k) {
      const double sq = std::sqrt(w_[k]);
      const double g = derivative_regressor(d_.log_pa[k], d_.log_pb[k], d_.inv_dp[k], c3);
      r[k] = sq * (d_.z[k] - c1 - c2 * g);
      if (jac != nullptr) {
        jac[k] = -sq;
        jac[n + k] = -sq * g;
        jac[2 * n + k] = -sq * c2 * derivative_regressor_dc3(d_.log_pa[k], d_.log_pb[k], d_.inv_dp[k], c3);
      }
    }
    return true;
  }

 private:
  const DerivativeData& d_;
  const std::vector<double>& w_;
};

double robust_weight(RobustLoss loss, double r, double scale) noexcept {
  const double a = std::abs(r);
  switch (loss) {
    case RobustLoss::huber: return a <= scale ? 1.0 : scale / a;
    case RobustLoss::cauchy: return 1.0 / (1.0 + (r / scale) * (r / scale));
    case RobustLoss::none: break;
  }
  return 1.0;
}

// Unweighted residuals at theta (offsets profiled with the current weights).
template <class Cost>
std::vector<double> plain_residuals(const Cost& cost, const double* theta, std::size_t n,
                                    const std::vector<double>& w) {
  std::vector<double> r(n);
  cost(theta, r.data(), nullptr);
  for (std::size_t k = 0; k < n; ++k) r[k] = w[k] > 0.0 ? r[k] / std::sqrt(w[k]) : 0.0;
  return r;
}

template <class Data, class Cost>
RefineOutcome irls(const Data& data, std::size_t n, const ScaledMem& start, const MemFitOptions& o, double scale) {
  const FitTimer timer(o.clock);
  RefineOutcome out;
  double theta[3] = {start.c1, start.c2, start.c3};
  std::vector<double> w(n, 1.0);
  const int outer = o.robust_loss == RobustLoss::none ? 1 : 3;
  for (int it = 0; it < outer; ++it) {
    if (o.robust_loss != RobustLoss::none) {
      Cost probe(data, w);
      const std::vector<double> r = plain_residuals(probe, theta, n, w);
      double moved = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const double wk = robust_weight(o.robust_loss, r[k], scale);
        moved = std::max(moved, std::abs(wk - w[k]));
        w[k] = wk;
      }
      if (it > 0 && moved < 1e-3) break;  // the weights have settled: the M-estimate is reached
    }
    Cost cost(data, w);
    ceres::TinySolver<Cost> solver;
    solver.options.max_num_iterations = o.max_solver_iterations;
    solver.options.gradient_tolerance = 1e-14;
    solver.options.parameter_tolerance = 1e-12;
    solver.options.function_tolerance = 1e-12;
    Eigen::Vector3d x(theta[0], theta[1], theta[2]);
    const double before[3] = {theta[0], theta[1], theta[2]};
    const auto summary = solver.Solve(cost, &x);
    ++out.ceres_solves;
    if (!x.allFinite()) {
      out.message =
          "non-finite parameters (TinySolver status " + std::to_string(static_cast<int>(summary.status)) + ")";
      return out;
    }
    theta[0] = x[0], theta[1] = x[1], theta[2] = x[2];
    double change = 0.0;
    for (int i = 0; i < 3; ++i)
      change = std::max(change, std::abs(theta[i] - before[i]) / std::max(std::abs(before[i]), 1e-12));
    if (change < 1e-9) break;
    // The time bound is checked between reweighting rounds (a round is a few ms).
    if (timer.elapsed_s() > o.max_solver_time_s) break;
  }
  out.usable = true;
  out.params = {theta[0], theta[1], theta[2]};
  return out;
}

}  // namespace

RefineOutcome refine(const IntegratedData& data, const ScaledMem& start, const MemFitOptions& options,
                     double loss_scale) {
  return irls<IntegratedData, IntegratedCost>(data, data.y.size(), start, options, loss_scale);
}

RefineOutcome refine(const DerivativeData& data, const ScaledMem& start, const MemFitOptions& options,
                     double loss_scale) {
  return irls<DerivativeData, DerivativeCost>(data, data.z.size(), start, options, loss_scale);
}

}  // namespace hystloop::detail
