// Prandtl-Ishlinskii NNLS fit and the linear baseline against known truth.
#include "ident/pi_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/errors.hpp"
#include "ident/linear_fit.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {
namespace {

std::vector<double> sine(double amp, double f, std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = amp * std::sin(2.0 * std::numbers::pi * f * static_cast<double>(k) * 1e-4);
  return u;
}

// The data come from the project's forward model (models/prandtl_ishlinskii.hpp, PiModel), not
// from the fitter's own predict_pi: a play operator wrong in both the fitter and predict_pi would
// otherwise fit its own output perfectly.
TEST(PiFit, RecoversWeightsOnItsOwnThresholds) {
  const auto u = sine(250.0, 10.0, 20000);  // starts at 0: PiModel's demagnetised state
  PiParams truth = PiParams::with_even_thresholds(15, 250.0);
  for (std::size_t i = 0; i < 15; ++i) truth.weights[i] = i % 3 == 1 ? 0.0 : 1e-9 / (1.0 + static_cast<double>(i));
  const double offset_m = 5e-9;
  PiModel model(truth);
  model.reset(0.0);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = offset_m + model.forward(u[k]);
  const PiFitResult r = fit_pi(u, y);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.weights.size(), 15u);
  // Noise-free data on the fit's own thresholds: NNLS solves the normal equations exactly, so
  // the errors are rounding (measured: weights 1.1e-11 w_0, offset ~1e-20 m). The bounds are ~100x
  // that and fail on any systematic error of 1e-9 w_0 (a threshold off by 1e-9 of the span does).
  double worst_w = 0.0;
  for (std::size_t i = 0; i < 15; ++i) {
    EXPECT_NEAR(r.thresholds_V[i], truth.thresholds[i], 1e-12 * 250.0);
    worst_w = std::max(worst_w, std::abs(r.weights[i] - truth.weights[i]) / truth.weights[0]);
    EXPECT_NEAR(r.weights[i], truth.weights[i], 1e-9 * truth.weights[0]) << i;
    EXPECT_GE(r.weights[i], 0.0);
  }
  std::printf("worst weight error %.2e w_0, offset error %.2e m, residual %.2e m\n", worst_w,
              std::abs(r.offset_m - offset_m), r.residual_rms_m);
  EXPECT_NEAR(r.offset_m, offset_m, 1e-18);
  EXPECT_LT(r.residual_rms_m, 1e-14);
}

TEST(PiFit, PlayOperatorIsABacklash) {
  const std::vector<double> u{0.0, 2.0, 3.0, 2.5, 1.0, 0.0};
  std::vector<double> out(u.size());
  play_operator(u, 1.0, 0.0, out);
  const std::vector<double> expect{0.0, 1.0, 2.0, 2.0, 2.0, 1.0};
  for (std::size_t k = 0; k < u.size(); ++k) EXPECT_DOUBLE_EQ(out[k], expect[k]) << k;
}

TEST(PiFit, RefusalsSayWhy) {
  const std::vector<double> flat(100, 1.0), y(100, 0.0);
  EXPECT_EQ(fit_pi(flat, y).status, FitStatus::constant_input);
  const auto u = sine(10.0, 10.0, 20000);
  const std::vector<double> zeros(u.size(), 0.0);
  const PiFitResult r = fit_pi(u, zeros);
  EXPECT_EQ(r.status, FitStatus::out_of_range) << r.reason;
  PiFitOptions bad;
  bad.operators = 0;
  EXPECT_THROW(fit_pi(u, zeros, bad), ParameterError);
}

TEST(LinearFit, RecoversGainAndOffset) {
  const auto u = sine(100.0, 3.0, 5000);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = 7e-9 * u[k] - 2e-8;
  const LinearFitResult r = fit_linear(u, y);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_NEAR(r.gain_m_per_V, 7e-9, 1e-20);
  EXPECT_NEAR(r.offset_m, -2e-8, 1e-18);
  std::vector<double> neg(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) neg[k] = -y[k];
  EXPECT_EQ(fit_linear(u, neg).status, FitStatus::out_of_range);
  EXPECT_EQ(fit_linear(std::vector<double>(10, 1.0), std::vector<double>(10, 0.0)).status, FitStatus::constant_input);
}

}  // namespace
}  // namespace hystloop
