// The checks every fitter makes on its data and its answer (ident/fit_checks.hpp).
#include "ident/fit_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace hystloop {
namespace {

TEST(FitChecks, SamplesMustBeFiniteAndWithinTheSanityBounds) {
  std::vector<double> u{0.0, 1.0, 2.0}, y{0.0, 1e-9, 2e-9};
  EXPECT_TRUE(check_fit_samples(u, y).ok());
  EXPECT_EQ(check_fit_samples(std::span(u).first(2), y).status, FitStatus::size_mismatch);
  EXPECT_EQ(check_fit_samples(std::span<const double>{}, std::span<const double>{}).status, FitStatus::size_mismatch);

  y[1] = std::numeric_limits<double>::quiet_NaN();
  FitCheck c = check_fit_samples(u, y);
  EXPECT_EQ(c.status, FitStatus::non_finite_data);
  EXPECT_NE(c.reason.find("sample 1"), std::string::npos) << c.reason;

  y[1] = 1e-9;
  u[2] = 2.5e302;  // the probe's data scaled by 1e300
  c = check_fit_samples(u, y);
  EXPECT_EQ(c.status, FitStatus::out_of_range);
  EXPECT_NE(c.reason.find("sample 2: u = "), std::string::npos) << c.reason;

  u[2] = -kFitMaxAbsVoltage_V;  // the bound itself is allowed
  EXPECT_TRUE(check_fit_samples(u, y).ok());
  y[0] = -1.5;
  c = check_fit_samples(u, y);
  EXPECT_EQ(c.status, FitStatus::out_of_range);
  EXPECT_NE(c.reason.find("sample 0: y = -1.5 m"), std::string::npos) << c.reason;
}

TEST(FitChecks, ResidualMustBeFiniteAndSmallerThanTheData) {
  EXPECT_TRUE(check_fit_residual(1e-9, 3e-6).ok());
  EXPECT_EQ(check_fit_residual(std::numeric_limits<double>::quiet_NaN(), 3e-6).status, FitStatus::solver_failure);
  EXPECT_EQ(check_fit_residual(-std::numeric_limits<double>::quiet_NaN(), 3e-6).status, FitStatus::solver_failure);
  EXPECT_EQ(check_fit_residual(std::numeric_limits<double>::infinity(), 3e-6).status, FitStatus::solver_failure);
  EXPECT_EQ(check_fit_residual(4e-6, 3e-6).status, FitStatus::out_of_range);
}

TEST(FitChecks, MemParamsOutsideTheirDomainAreRefused) {
  EXPECT_TRUE(check_valid(MemParams::paper_like(), "MEM: ").ok());
  MemParams p;
  p.c2 = std::numeric_limits<double>::quiet_NaN();
  const FitCheck c = check_valid(p, "MEM: ");
  EXPECT_EQ(c.status, FitStatus::out_of_range);
  EXPECT_NE(c.reason.find("c2"), std::string::npos) << c.reason;
  p = MemParams::paper_like();
  p.c1 = 0.0;
  EXPECT_EQ(check_valid(p, "MEM: ").status, FitStatus::out_of_range);
}

TEST(FitChecks, KatalenicBandMustBeDeterminedByTheData) {
  KatalenicParams p;  // k1 40 V, k2 0.01 1/V
  p.k2_slope = 0.0;
  EXPECT_TRUE(check_katalenic_params(p, 500.0).ok());
  p.k1 = 5.4e301;  // what the probe got on data scaled by 1e300
  FitCheck c = check_katalenic_params(p, 500.0);
  EXPECT_EQ(c.status, FitStatus::out_of_range);
  EXPECT_NE(c.reason.find("k1 = "), std::string::npos) << c.reason;
  p.k1 = 40.0;
  p.k2 = 1e-12;
  c = check_katalenic_params(p, 500.0);
  EXPECT_EQ(c.status, FitStatus::out_of_range);
  EXPECT_NE(c.reason.find("k2 = "), std::string::npos) << c.reason;
  p.k2 = std::numeric_limits<double>::infinity();
  EXPECT_EQ(check_katalenic_params(p, 500.0).status, FitStatus::out_of_range);
}

}  // namespace
}  // namespace hystloop
