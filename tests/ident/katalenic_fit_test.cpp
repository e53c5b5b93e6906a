// Katalenic operator fit against data from KatalenicModel with known parameters.
#include "ident/katalenic_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "core/errors.hpp"

namespace hystloop {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kSamples = 10000;  // 1 s under the sanitizer (the fit simulates the operator)
constexpr double kSolverTime = 60.0;     // the 2 s default is a Release figure
#else
constexpr std::size_t kSamples = 20000;
constexpr double kSolverTime = 2.0;
#endif

std::vector<double> paper_input() {
  std::vector<double> u(kSamples);
  for (std::size_t k = 0; k < u.size(); ++k)
    u[k] = 250.0 * std::sin(2.0 * std::numbers::pi * 10.0 * static_cast<double>(k) * 1e-4);
  return u;
}

std::vector<double> simulate(const KatalenicParams& p, const std::vector<double>& u) {
  KatalenicModel m(p);
  m.reset(u[0]);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = m.forward(u[k]);
  return y;
}

TEST(KatalenicFit, RecoversTheOperatorAndLinearShaping) {
  KatalenicParams truth;  // k1 40 V, k2 0.01 /V, output gain 3.79 nm/V
  truth.k2_slope = 0.0;
  const auto u = paper_input();
  auto y = simulate(truth, u);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1e-9);
  for (double& v : y) v += n(rng);
  KatalenicFitOptions o;
  o.max_solver_time_s = kSolverTime;
  o.clock = fixed_fit_clock();  // Ceres ends on its tolerances, whatever the machine's load
  const KatalenicFitResult r = fit_katalenic(u, y, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  const double e_k1 = std::abs(r.params.k1 / truth.k1 - 1.0), e_k2 = std::abs(r.params.k2 / truth.k2 - 1.0);
  const double e_gain = std::abs(r.params.output_shaping.gain / truth.output_shaping.gain - 1.0);
  std::printf("rel. errors: k1 %.2e, k2 %.2e, gain %.2e\n", e_k1, e_k2, e_gain);
  // Seeded 1 nm noise on a 20,000-sample loop (Release): measured k1 1.4e-4, k2 2.2e-4, gain
  // 9.9e-6, the noise's share of one draw. Bounds ~5x above (a 1-2 % bound let a real bias pass);
  // The sanitizer build's 10,000 samples are another, shorter draw: gain 8.3e-5 measured there
  // (Debug + ASan, fresh clone), hence the factor 3 for it.
  const double widen = kSamples < 20000 ? 3.0 : 1.0;
  EXPECT_LT(e_k1, widen * 7e-4);
  EXPECT_LT(e_k2, widen * 1e-3);
  EXPECT_LT(e_gain, widen * 5e-5);
  EXPECT_NEAR(r.residual_rms_m, 1e-9, 0.1e-9);
}

TEST(KatalenicFit, RefusalsSayWhy) {
  const std::vector<double> flat(500, 1.0), y(500, 0.0);
  const KatalenicFitResult c = fit_katalenic(flat, y);
  EXPECT_EQ(c.status, FitStatus::constant_input) << c.reason;
  std::vector<double> ramp(500);
  for (std::size_t k = 0; k < ramp.size(); ++k) ramp[k] = static_cast<double>(k);
  EXPECT_EQ(fit_katalenic(ramp, y).status, FitStatus::too_few_branches);
  EXPECT_EQ(fit_katalenic(std::span(ramp).first(3), y).status, FitStatus::size_mismatch);
  KatalenicFitOptions bad;
  bad.output_polynomial_degree = 0;
  EXPECT_THROW(fit_katalenic(ramp, y, bad), ParameterError);
}

// The probe's case: valid data scaled by 1e300 "fitted" k1 = 5.4e301 and exited 0.
TEST(KatalenicFit, DataScaledBeyondPhysicsIsRefusedNotFitted) {
  KatalenicParams truth;
  truth.k2_slope = 0.0;
  auto u = paper_input();
  u.resize(4000);
  auto y = simulate(truth, u);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] *= 1e300, y[k] *= 1e300;
  const KatalenicFitResult r = fit_katalenic(u, y);
  EXPECT_FALSE(r.ok()) << "k1 = " << r.params.k1;
  EXPECT_EQ(r.status, FitStatus::out_of_range) << r.reason;
  EXPECT_NE(r.reason.find("sanity bound"), std::string::npos) << r.reason;
}

}  // namespace
}  // namespace hystloop
