#pragma once
// Non-negative least squares, min ||A x - b|| subject to x >= 0, by the active-set method of
// Lawson & Hanson (1974, ch. 23). Why our own: Eigen 3.4 as shipped by Debian 12 has no NNLS
// (unsupported/Eigen/NNLS arrived after 3.4), and Prandtl-Ishlinskii weights must be >= 0 for the
// model to be monotone and invertible.
// Works on the normal equations (G = A'A, h = A'b): the problems here are tall (10^4 rows) and
// narrow (tens of columns), so forming G once makes every inner solve tiny.

#include <Eigen/Core>

namespace hystloop {

struct NnlsResult {
  Eigen::VectorXd x;
  int iterations = 0;
  bool converged = false;  // KKT conditions met within the tolerance
};

NnlsResult nnls(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int max_iterations = 0);

}  // namespace hystloop
