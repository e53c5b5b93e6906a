#include "ident/nnls.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <limits>
#include <vector>

namespace hystloop {
namespace {

// Least squares restricted to the passive set P: solves G_PP z_P = h_P, z = 0 elsewhere.
Eigen::VectorXd solve_passive(const Eigen::MatrixXd& g, const Eigen::VectorXd& h, const std::vector<bool>& passive) {
  std::vector<Eigen::Index> idx;
  for (Eigen::Index i = 0; i < h.size(); ++i)
    if (passive[static_cast<std::size_t>(i)]) idx.push_back(i);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(h.size());
  if (idx.empty()) return z;
  const auto m = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd gp(m, m);
  Eigen::VectorXd hp(m);
  for (Eigen::Index r = 0; r < m; ++r) {
    hp[r] = h[idx[static_cast<std::size_t>(r)]];
    for (Eigen::Index c = 0; c < m; ++c)
      gp(r, c) = g(idx[static_cast<std::size_t>(r)], idx[static_cast<std::size_t>(c)]);
  }
  const Eigen::VectorXd zp = gp.ldlt().solve(hp);
  for (Eigen::Index r = 0; r < m; ++r) z[idx[static_cast<std::size_t>(r)]] = zp[r];
  return z;
}

NnlsResult nnls_normal(const Eigen::MatrixXd& g, const Eigen::VectorXd& h, int max_iterations) {
  const Eigen::Index n = h.size();
  if (max_iterations <= 0) max_iterations = static_cast<int>(3 * n + 10);
  NnlsResult res;
  res.x = Eigen::VectorXd::Zero(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  const double tol = 1e-12 * std::max(1.0, g.diagonal().cwiseAbs().maxCoeff()) * std::max(1.0, h.cwiseAbs().maxCoeff());
  for (; res.iterations < max_iterations; ++res.iterations) {
    const Eigen::VectorXd w = h - g * res.x;  // negative gradient
    Eigen::Index best = -1;
    double wmax = tol;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!passive[static_cast<std::size_t>(i)] && w[i] > wmax) wmax = w[i], best = i;
    }
    if (best < 0) {
      res.converged = true;
      return res;
    }
    passive[static_cast<std::size_t>(best)] = true;
    // Inner loop: step towards the unconstrained passive solution until it is feasible.
    for (int inner = 0; inner < 3 * n + 10; ++inner) {
      const Eigen::VectorXd z = solve_passive(g, h, passive);
      bool feasible = true;
      double alpha = 1.0;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<std::size_t>(i)] && z[i] <= 0.0) {
          feasible = false;
          const double denom = res.x[i] - z[i];
          if (denom > 0.0) alpha = std::min(alpha, res.x[i] / denom);
        }
      }
      if (feasible) {
        res.x = z;
        break;
      }
      res.x += alpha * (z - res.x);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<std::size_t>(i)] && res.x[i] <= 1e-15 * std::max(1.0, res.x.cwiseAbs().maxCoeff())) {
          passive[static_cast<std::size_t>(i)] = false;
          res.x[i] = 0.0;
        }
      }
    }
  }
  return res;
}

}  // namespace

NnlsResult nnls(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int max_iterations) {
  const Eigen::MatrixXd g = a.transpose() * a;
  const Eigen::VectorXd h = a.transpose() * b;
  return nnls_normal(g, h, max_iterations);
}

}  // namespace hystloop
