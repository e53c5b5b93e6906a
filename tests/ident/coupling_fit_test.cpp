// The coupling fit (ident/coupling_fit.hpp) against simulated one-axis-at-a-time experiments with
// a known C, and each of its refusals.

#include "ident/coupling_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "support/refusal.hpp"
#include "support/typical_coupling.hpp"

namespace hystloop {
namespace {

constexpr double kNoise_m = 1e-9;        // Gaussian sensor noise on every axis
constexpr double kAmplitude_m = 0.5e-6;  // the excited axis's triangle: +-0.5 um
constexpr std::size_t kSamples = 4000;   // per experiment: 4 periods of 1000
constexpr std::size_t kPeriod = 1000;

AxisMatrix truth() { return testing::typical_coupling(); }

// Where the held axes sit: not at 0, so a fit without an offset would be biased.
constexpr double kHeld_m[kMaxAxes] = {0.2e-6, -0.1e-6, 0.35e-6};

// The recorded sensors of one experiment (the AxisExcitation views point into them).
struct Experiment {
  int axis = 0;
  std::array<std::vector<double>, kMaxAxes> y;

  AxisExcitation view(int n) const {
    AxisExcitation e;
    e.axis = axis;
    for (std::size_t j = 0; j < static_cast<std::size_t>(n); ++j) e.y_m[j] = y[j];
    return e;
  }
};

double triangle(double amplitude_m, std::size_t t) {
  const double p = static_cast<double>(t % kPeriod) / static_cast<double>(kPeriod);
  return amplitude_m * (4.0 * std::abs(p - 0.5) - 1.0);
}

// Axis `axis` runs a triangle of +-amplitude about its held position, the others stay held; the
// sensors read y = C s plus independent noise.
Experiment simulate(const AxisMatrix& c, int n, int axis, double amplitude_m, std::mt19937_64& rng,
                    std::size_t samples = kSamples) {
  std::normal_distribution<double> noise(0.0, kNoise_m);
  Experiment e;
  e.axis = axis;
  for (int j = 0; j < n; ++j) e.y[static_cast<std::size_t>(j)].resize(samples);
  for (std::size_t t = 0; t < samples; ++t) {
    AxisVector s(kHeld_m[0], kHeld_m[1], kHeld_m[2]);
    s(axis) += triangle(amplitude_m, t);
    const AxisVector y = c * s;
    for (int j = 0; j < n; ++j) e.y[static_cast<std::size_t>(j)][t] = y(j) + noise(rng);
  }
  return e;
}

std::vector<Experiment> simulate_all(const AxisMatrix& c, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Experiment> out;
  out.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out.push_back(simulate(c, n, i, kAmplitude_m, rng));
  return out;
}

std::vector<AxisExcitation> views(const std::vector<Experiment>& experiments, int n) {
  std::vector<AxisExcitation> out;
  out.reserve(experiments.size());
  for (const Experiment& e : experiments) out.push_back(e.view(n));
  return out;
}

CouplingFitOptions axes(int n) {
  CouplingFitOptions o;
  o.axes = n;
  return o;
}

bool mentions(const std::string& reason, const std::string& part) { return reason.find(part) != std::string::npos; }

// The standard error a slope should have: sigma / sqrt(sum (x - mean)^2), the triangle's sum being
// N A^2 / 3 (the sensor noise on the residual is sqrt(1 + C_ji^2) sigma ~ sigma).
double expected_standard_error() {
  return kNoise_m / std::sqrt(static_cast<double>(kSamples) * kAmplitude_m * kAmplitude_m / 3.0);  // 5.5e-5
}

// Tolerance: every entry within 4 of its own standard errors (a 6.3e-5 chance per entry for a
// Gaussian estimate), each standard error below 1e-4 and within 10 % of what 1 nm of noise on this
// triangle gives (its own scatter at 4000 samples is ~1 %). Decoupled with the fitted C, the
// stage's residual coupling C_true C_fit^{-1} - I has entries ~ -(C_fit - C_true)_ji (plus a few
// per cent of the other entries' errors): bound 2.5e-4 = 4 x 5.5e-5 + 10 %, against 3 % before.
TEST(CouplingFit, RecoversAKnownMatrix) {
  const auto experiments = simulate_all(truth(), 3, 20240611);
  const auto excitations = views(experiments, 3);
  const CouplingFitResult r = fit_coupling(excitations);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(r.samples_used, 3 * kSamples);
  EXPECT_EQ(r.coupling.n(), 3);
  double worst_sigmas = 0.0, worst_error = 0.0, worst_se = 0.0;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(r.coupling.matrix()(j, i), r.estimate(j, i));
      if (i == j) {
        EXPECT_EQ(r.estimate(j, i), 1.0);
        EXPECT_EQ(r.standard_error(j, i), 0.0);
        continue;
      }
      const double se = r.standard_error(j, i), error = r.estimate(j, i) - truth()(j, i);
      EXPECT_LT(se, 1e-4) << j << i;
      EXPECT_NEAR(se, expected_standard_error(), 0.1 * expected_standard_error()) << j << i;
      EXPECT_LE(std::abs(error), 4.0 * se) << "C[" << j << "][" << i << "] = " << r.estimate(j, i);
      // The residual is the sensor noise: the line explains the rest.
      EXPECT_NEAR(r.line_residual_rms_m(j, i), kNoise_m, 0.05 * kNoise_m) << j << i;
      worst_sigmas = std::max(worst_sigmas, std::abs(error) / se);
      worst_error = std::max(worst_error, std::abs(error));
      worst_se = std::max(worst_se, se);
    }
  }
  const AxisMatrix residual = truth() * r.coupling.inverse_matrix() - AxisMatrix::Identity();
  const AxisMatrix before = truth() - AxisMatrix::Identity();
  std::printf("worst |error| %.2e (%.2f standard errors), worst standard error %.2e, expected %.2e\n", worst_error,
              worst_sigmas, worst_se, expected_standard_error());
  std::printf("residual coupling after decoupling: max %.2e (before %.2e); fit: %s\n", residual.cwiseAbs().maxCoeff(),
              before.cwiseAbs().maxCoeff(), r.coupling.describe().c_str());
  EXPECT_LT(residual.cwiseAbs().maxCoeff(), 2.5e-4);
  EXPECT_LE(r.residual_rms_m, 1.05 * kNoise_m);
}

// Two axes, x barely coupled: the same slopes on a 2-axis stage (z spans absent).
TEST(CouplingFit, TwoAxes) {
  const auto experiments = simulate_all(truth(), 2, 5);
  const CouplingFitResult r = fit_coupling(views(experiments, 2), axes(2));
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(r.coupling.n(), 2);
  EXPECT_NEAR(r.estimate(1, 0), 0.03, 4.0 * r.standard_error(1, 0));
  EXPECT_NEAR(r.estimate(0, 1), -0.01, 4.0 * r.standard_error(0, 1));
  EXPECT_EQ(r.estimate(2, 0), 0.0);
  EXPECT_EQ(r.samples_used, 2 * kSamples);
}

TEST(CouplingFit, RefusesTooLittleTravel) {
  std::mt19937_64 rng(11);
  std::vector<Experiment> experiments;
  experiments.push_back(simulate(truth(), 3, 0, kAmplitude_m, rng));
  experiments.push_back(simulate(truth(), 3, 1, 20e-9, rng));  // 40 nm peak to peak (+ noise) < 50 nm
  experiments.push_back(simulate(truth(), 3, 2, kAmplitude_m, rng));
  const CouplingFitResult r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::constant_input);
  EXPECT_TRUE(mentions(r.reason, "y spans")) << r.reason;
  EXPECT_TRUE(r.coupling.matrix().isIdentity(0.0));
  // The same travel passes a lower minimum.
  CouplingFitOptions lower;
  lower.min_travel_m = 30e-9;
  EXPECT_TRUE(fit_coupling(views(experiments, 3), lower).ok());
}

TEST(CouplingFit, RefusesMismatchedLengths) {
  auto experiments = simulate_all(truth(), 3, 12);
  experiments[0].y[2].pop_back();
  const CouplingFitResult r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::size_mismatch);
  EXPECT_TRUE(mentions(r.reason, "experiment 0 (x moved): z has 3999 samples, x has 4000")) << r.reason;

  // Spans beyond the fit's axes are a mismatch too (a 3-axis recording fitted as 2 axes).
  auto three = simulate_all(truth(), 2, 12);
  three[1].y[2].assign(kSamples, 0.0);
  auto excitations = views(three, 2);
  excitations[1].y_m[2] = three[1].y[2];
  const CouplingFitResult beyond = fit_coupling(excitations, axes(2));
  EXPECT_EQ(beyond.status, FitStatus::size_mismatch);
  EXPECT_TRUE(mentions(beyond.reason, "z has 4000 samples, but the fit has 2 axes")) << beyond.reason;
}

TEST(CouplingFit, RefusesNonFiniteAndInsaneSamples) {
  auto experiments = simulate_all(truth(), 3, 13);
  experiments[2].y[1][17] = std::numeric_limits<double>::quiet_NaN();
  CouplingFitResult r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::non_finite_data);
  EXPECT_TRUE(mentions(r.reason, "experiment 2 (z moved): sample 17 of y is not finite")) << r.reason;

  experiments[2].y[1][17] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(fit_coupling(views(experiments, 3)).status, FitStatus::non_finite_data);

  experiments[2].y[1][17] = 2.0;  // a sensor in volts?
  r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::out_of_range);
  EXPECT_TRUE(mentions(r.reason, "sample 17 of y is 2 m, beyond the sanity bound")) << r.reason;
}

TEST(CouplingFit, RefusesAnAxisMovedTwice) {
  std::mt19937_64 rng(14);
  std::vector<Experiment> experiments;
  for (int axis : {0, 1, 0, 2}) experiments.push_back(simulate(truth(), 3, axis, kAmplitude_m, rng));
  const CouplingFitResult r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::size_mismatch);
  EXPECT_TRUE(mentions(r.reason, "axis x is moved by experiments 0 and 2")) << r.reason;
  EXPECT_TRUE(r.coupling.matrix().isIdentity(0.0));
}

TEST(CouplingFit, AnUnexcitedAxisIsRefusedUnlessAllowed) {
  std::mt19937_64 rng(15);
  std::vector<Experiment> experiments;
  experiments.push_back(simulate(truth(), 3, 0, kAmplitude_m, rng));
  experiments.push_back(simulate(truth(), 3, 1, kAmplitude_m, rng));
  const CouplingFitResult refused = fit_coupling(views(experiments, 3));
  EXPECT_EQ(refused.status, FitStatus::too_few_samples);
  EXPECT_TRUE(mentions(refused.reason, "no experiment moves axis z")) << refused.reason;

  CouplingFitOptions allow;
  allow.allow_unexcited_axes = true;
  const CouplingFitResult r = fit_coupling(views(experiments, 3), allow);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_TRUE(r.excited[0] && r.excited[1] && !r.excited[2]);
  // z's column is assumed uncoupled, not measured ...
  EXPECT_EQ(r.estimate(0, 2), 0.0);
  EXPECT_EQ(r.estimate(1, 2), 0.0);
  EXPECT_TRUE(std::isnan(r.standard_error(0, 2)));
  EXPECT_TRUE(std::isnan(r.standard_error(1, 2)));
  // ... while its row, what x and y do to z, is fitted from their experiments.
  EXPECT_NEAR(r.estimate(2, 0), 0.005, 4.0 * r.standard_error(2, 0));
  EXPECT_NEAR(r.estimate(2, 1), 0.015, 4.0 * r.standard_error(2, 1));
  EXPECT_NEAR(r.estimate(1, 0), 0.03, 4.0 * r.standard_error(1, 0));
  EXPECT_EQ(r.samples_used, 2 * kSamples);
}

TEST(CouplingFit, RefusesOtherMalformedExperiments) {
  auto experiments = simulate_all(truth(), 3, 16);
  auto excitations = views(experiments, 3);
  EXPECT_EQ(fit_coupling({}).status, FitStatus::too_few_samples);

  excitations[2].axis = 3;
  CouplingFitResult r = fit_coupling(excitations);
  EXPECT_EQ(r.status, FitStatus::out_of_range);
  EXPECT_TRUE(mentions(r.reason, "experiment 2 moves axis 3, but the fit has 3 axes")) << r.reason;

  std::mt19937_64 rng(17);
  std::vector<Experiment> short_ones;
  short_ones.reserve(3);
  for (int axis = 0; axis < 3; ++axis) short_ones.push_back(simulate(truth(), 3, axis, kAmplitude_m, rng, 99));
  r = fit_coupling(views(short_ones, 3));
  EXPECT_EQ(r.status, FitStatus::too_few_samples);
  EXPECT_TRUE(mentions(r.reason, "99 samples (need 100)")) << r.reason;
}

// A fitted matrix AxisCoupling refuses (here a 60 % "coupling": a mislabelled sensor) is refused
// with its field, the estimate kept for the report and the coupling left at the identity.
TEST(CouplingFit, RefusesAFittedMatrixAxisCouplingRefuses) {
  AxisMatrix c = truth();
  c(1, 0) = 0.6;
  const auto experiments = simulate_all(c, 3, 18);
  const CouplingFitResult r = fit_coupling(views(experiments, 3));
  EXPECT_EQ(r.status, FitStatus::out_of_range);
  EXPECT_TRUE(mentions(r.reason, "coupling[1][0]")) << r.reason;
  EXPECT_NEAR(r.estimate(1, 0), 0.6, 1e-3);
  EXPECT_TRUE(r.coupling.matrix().isIdentity(0.0));
}

TEST(CouplingFit, OptionsNameTheField) {
  auto field_of = [](const CouplingFitOptions& o) {
    const auto e = testing::thrown<ParameterError>([&] { o.validate(); });
    return e ? e->field() : std::string("accepted");
  };
  CouplingFitOptions o;
  EXPECT_EQ(field_of(o), "accepted");
  o.axes = 0;
  EXPECT_EQ(field_of(o), "axes");
  o.axes = 4;
  EXPECT_EQ(field_of(o), "axes");
  o = {};
  o.min_travel_m = 0.0;
  EXPECT_EQ(field_of(o), "min_travel_m");
  o = {};
  o.min_samples = 2;
  EXPECT_EQ(field_of(o), "min_samples");
  o.min_samples = 3;
  EXPECT_EQ(field_of(o), "accepted");
  EXPECT_THROW(fit_coupling({}, CouplingFitOptions{.axes = 0}), ParameterError);
}

}  // namespace
}  // namespace hystloop
