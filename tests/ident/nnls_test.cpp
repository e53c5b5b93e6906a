// Lawson-Hanson NNLS: KKT conditions on seeded random problems, known answers.
#include "ident/nnls.hpp"

#include <gtest/gtest.h>

#include <random>

namespace hystloop {
namespace {

TEST(Nnls, UnconstrainedOptimumInsideTheOrthantIsReturned) {
  Eigen::MatrixXd a(4, 2);
  a << 1, 0, 0, 1, 1, 1, 2, 1;
  const Eigen::Vector2d x_true(0.5, 2.0);
  const Eigen::VectorXd b = a * x_true;
  const NnlsResult r = nnls(a, b);
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.x[0], 0.5, 1e-12);
  EXPECT_NEAR(r.x[1], 2.0, 1e-12);
}

TEST(Nnls, NegativeComponentIsClampedToZero) {
  // min (x0 - 1)^2 + (x1 + 1)^2: the answer is (1, 0).
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(2, 2);
  const NnlsResult r = nnls(a, Eigen::Vector2d(1.0, -1.0));
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.x[0], 1.0, 1e-12);
  EXPECT_EQ(r.x[1], 0.0);
}

// Seeded random problems: the KKT conditions x >= 0, w = A'(b - Ax) <= 0, w_i = 0 where x_i > 0.
TEST(Nnls, KktConditionsHoldOnRandomProblems) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 30, cols = 1 + trial % 12;
    Eigen::MatrixXd a(rows, cols);
    Eigen::VectorXd b(rows);
    for (int i = 0; i < rows; ++i) {
      b[i] = n(rng);
      for (int j = 0; j < cols; ++j) a(i, j) = n(rng);
    }
    const NnlsResult r = nnls(a, b);
    ASSERT_TRUE(r.converged) << trial;
    const Eigen::VectorXd w = a.transpose() * (b - a * r.x);
    for (int j = 0; j < cols; ++j) {
      EXPECT_GE(r.x[j], 0.0);
      EXPECT_LE(w[j], 1e-9) << trial;
      if (r.x[j] > 1e-12) {
        EXPECT_NEAR(w[j], 0.0, 1e-9) << trial;
      }
    }
  }
}

}  // namespace
}  // namespace hystloop
