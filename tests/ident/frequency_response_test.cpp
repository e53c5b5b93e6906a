// The robust-method FRF on the tests' two-mode stage (two_mode_stage.hpp) with white output noise
// of known standard deviation: bias and spread of G and of its sigma estimates within the bounds
// derived in frequency_response.hpp; a static nonlinearity shows as sigma_total above sigma_noise.
#include "ident/frequency_response.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/errors.hpp"
#include "models/multisine.hpp"
#include "ident/two_mode_stage.hpp"

namespace hystloop {
namespace {

constexpr std::size_t kN = 2000, kP = 6, kR = 4;

MultisineOptions excitation() {
  MultisineOptions o;
  o.period_samples = kN;  // 5 Hz lines
  o.f_min_Hz = 5.0;
  o.f_max_Hz = 3000.0;  // 600 lines
  o.amplitude_V = 1.0;  // rms
  o.periods = kP;
  o.realisations = kR;
  o.seed = 42;
  return o;
}

FrfOptions frf_options() {
  FrfOptions f;
  f.period_samples = kN;
  f.periods = kP;
  f.realisations = kR;
  f.transient_periods = 1;
  return f;
}

TEST(FrequencyResponse, NoiseFreeEstimateIsTheSampledResponse) {
  test::TwoModeStage stage;
  const Multisine m = design_multisine(excitation());
  const auto y = stage.simulate(m.u_V, 0.0, 1);
  const FrequencyResponse r = estimate_frequency_response(m.u_V, y, m.lines, frf_options());
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.G.size(), 600u);
  double worst = 0.0;
  for (std::size_t i = 0; i < r.G.size(); i += 7) {  // the aliasing sum is slow: every 7th line
    worst = std::max(worst, std::abs(r.G[i] - stage.sampled_response(r.frequency_Hz[i])));
  }
  std::printf("noise-free: max |G - G0| = %.2e\n", worst);
  EXPECT_LT(worst, 1e-10);  // measured 1.3e-13: the transient is e^-29 down after a period, the sum's tail ~1e-10
  for (double c : r.coherence) EXPECT_NEAR(c, 1.0, 1e-12);
}

struct NoisyRun {
  FrequencyResponse frf;
  std::vector<std::complex<double>> truth;
  double sigma_theory = 0.0;  // (1) of the header
};

NoisyRun noisy_run(double noise_sd, double cubic = 0.0) {
  test::TwoModeStage stage;
  const Multisine m = design_multisine(excitation());
  auto y = stage.simulate(m.u_V, noise_sd, 99);
  if (cubic != 0.0) {  // a static nonlinearity on the output (before the noise would be the same here)
    const auto clean = stage.simulate(m.u_V, 0.0, 99);
    for (std::size_t i = 0; i < y.size(); ++i) y[i] += cubic * std::pow(clean[i], 3);
  }
  NoisyRun run;
  run.frf = estimate_frequency_response(m.u_V, y, m.lines, frf_options());
  // The noise-free estimate is the sampled response to 1e-10 (test above), far below sigma: use it
  // as the truth instead of the slow aliasing sum.
  const auto y0 = stage.simulate(m.u_V, 0.0, 1);
  run.truth = estimate_frequency_response(m.u_V, y0, m.lines, frf_options()).G;
  const double A = m.line_amplitude_V[0];
  run.sigma_theory = 2.0 * noise_sd / (A * std::sqrt(static_cast<double>(kN * (kP - 1) * kR)));
  return run;
}

TEST(FrequencyResponse, BiasAndSpreadWithinTheDerivedBounds) {
  const NoisyRun run = noisy_run(0.01);
  const FrequencyResponse& r = run.frf;
  ASSERT_TRUE(r.ok()) << r.reason;
  const double F = static_cast<double>(r.G.size()), s2 = run.sigma_theory * run.sigma_theory;
  double err2 = 0.0, worst = 0.0, mag_bias = 0.0, vn = 0.0, vt = 0.0;
  for (std::size_t i = 0; i < r.G.size(); ++i) {
    const double e2 = std::norm(r.G[i] - run.truth[i]) / s2;
    err2 += e2 / F;
    worst = std::max(worst, std::sqrt(e2));
    mag_bias += (std::abs(r.G[i]) - std::abs(run.truth[i])) / run.sigma_theory / F;
    vn += r.sigma_noise[i] * r.sigma_noise[i] / s2 / F;
    vt += r.sigma_total[i] * r.sigma_total[i] / s2 / F;
  }
  std::printf(
      "sigma_G %.3e: mean |e|^2/s^2 %.4f, max |e|/s %.2f, |G| bias %.4f s, noise var %.4f, total var %.4f, "
      "distortion ratio %.3f\n",
      run.sigma_theory, err2, worst, mag_bias, vn, vt, r.distortion_ratio);
  // Four standard deviations of each mean (header), and the 1e-6 tail for the worst line.
  EXPECT_NEAR(err2, 1.0, 4.0 / std::sqrt(F));
  EXPECT_LT(worst, 4.5);
  EXPECT_NEAR(mag_bias, 0.0, 4.0 / std::sqrt(2.0 * F));
  EXPECT_NEAR(vn, 1.0, 4.0 / std::sqrt(F * kR * (kP - 2)));
  EXPECT_NEAR(vt, 1.0, 4.0 / std::sqrt(F * (kR - 1)));
  // sigma_noise^2 has 40 degrees of freedom per line, sigma_total^2 6: their ratio's mean over the
  // lines is 1 +- ~1/sqrt(F (R - 1)).
  EXPECT_NEAR(r.distortion_ratio, 1.0, 5.0 / std::sqrt(F * (kR - 1)));
  // Per line: sigma_noise within 4 relative standard deviations 1/sqrt(R (P - 1)) on all but ~1e-4 of the lines.
  std::size_t outside = 0;
  for (double s : r.sigma_noise)
    if (std::abs(s * s / s2 - 1.0) > 4.0 / std::sqrt(kR * (kP - 2.0))) ++outside;
  EXPECT_LE(outside, 1u);
  EXPECT_TRUE(r.total_available);
}

TEST(FrequencyResponse, InputNoiseEntersTheVariance) {
  // A measured input: white noise on the u record the estimator sees (the stage is driven by the
  // clean one). Then G - G0 ~ -G0 N_U / U, of variance |G0|^2 4 s_u^2 / (N P R A^2): the
  // first-order variance (header) must account for it, line by line, as it does for output noise.
  test::TwoModeStage stage;
  const Multisine m = design_multisine(excitation());
  const auto y = stage.simulate(m.u_V, 0.0, 1);
  std::vector<double> u_measured(m.u_V);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double& v : u_measured) v += noise(rng);
  const FrequencyResponse r = estimate_frequency_response(u_measured, y, m.lines, frf_options());
  const FrequencyResponse clean = estimate_frequency_response(m.u_V, y, m.lines, frf_options());
  ASSERT_TRUE(r.ok()) << r.reason;
  const double F = static_cast<double>(r.G.size());
  const double s_u = 2.0 * 0.01 / (m.line_amplitude_V[0] * std::sqrt(static_cast<double>(kN * (kP - 1) * kR)));
  double err2 = 0.0, vn = 0.0;
  for (std::size_t i = 0; i < r.G.size(); ++i) {
    const double s2 = std::norm(clean.G[i]) * s_u * s_u;
    err2 += std::norm(r.G[i] - clean.G[i]) / (r.sigma_noise[i] * r.sigma_noise[i]) / F;
    vn += r.sigma_noise[i] * r.sigma_noise[i] / s2 / F;
  }
  std::printf("input noise: mean |e|^2 / sigma_noise^2 %.4f, sigma_noise^2 / theory %.4f\n", err2, vn);
  // |e|^2 / sigma_noise^2 with sigma_noise^2 of nu = 2 R (P - 1) = 40 degrees of freedom has mean
  // nu / (nu - 2) and a standard deviation ~1.1 per line: 4 of them over F lines.
  EXPECT_NEAR(err2, 40.0 / 38.0, 4.5 / std::sqrt(F));
  EXPECT_NEAR(vn, 1.0, 4.0 / std::sqrt(F * kR * (kP - 2)));
}

TEST(FrequencyResponse, NonlinearDistortionRaisesTheTotalVarianceOnly) {
  const NoisyRun lin = noisy_run(0.01);
  const NoisyRun nl = noisy_run(0.01, 0.2);
  ASSERT_TRUE(nl.frf.ok()) << nl.frf.reason;
  std::printf("distortion ratio: linear %.3f, cubic %.3f\n", lin.frf.distortion_ratio, nl.frf.distortion_ratio);
  EXPECT_GT(nl.frf.distortion_ratio, 5.0);
  // The noise estimate does not see the distortion (it is periodic).
  double vn_lin = 0.0, vn_nl = 0.0;
  for (std::size_t i = 0; i < lin.frf.G.size(); ++i) vn_lin += lin.frf.sigma_noise[i], vn_nl += nl.frf.sigma_noise[i];
  EXPECT_NEAR(vn_nl / vn_lin, 1.0, 0.05);
}

TEST(FrequencyResponse, RefusesBadRecords) {
  const Multisine m = design_multisine(excitation());
  std::vector<double> y(m.u_V.size(), 0.0);
  std::vector<double> short_y(y.begin(), y.end() - 1);
  EXPECT_EQ(estimate_frequency_response(m.u_V, short_y, m.lines, frf_options()).status, FitStatus::size_mismatch);
  y[1234] = std::nan("");
  const FrequencyResponse nan = estimate_frequency_response(m.u_V, y, m.lines, frf_options());
  EXPECT_EQ(nan.status, FitStatus::non_finite_data);
  EXPECT_NE(nan.reason.find("1234"), std::string::npos) << nan.reason;
  y[1234] = 0.0;
  const std::vector<std::size_t> beyond{10, 1000};
  EXPECT_EQ(estimate_frequency_response(m.u_V, y, beyond, frf_options()).status, FitStatus::out_of_range);
  const std::vector<std::size_t> unexcited{10, 1000 - 1, 2};  // line 999 is not excited (band to 3 kHz)
  EXPECT_EQ(estimate_frequency_response(m.u_V, y, unexcited, frf_options()).status, FitStatus::constant_input);
  FrfOptions o = frf_options();
  o.transient_periods = 5;  // leaves one period: no noise variance
  try {
    estimate_frequency_response(m.u_V, y, m.lines, o);
    ADD_FAILURE() << "no throw";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "periods");
  }
}

}  // namespace
}  // namespace hystloop
