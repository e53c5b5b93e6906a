// Taking the stage out of measured samples: the hysteresis' output recovered from the stage's
// position, one sample late; breaks hand out the held sample; a fit on the removed samples finds
// the hysteresis that a fit of u -> y blurs with the stage's lag.
#include "ident/stage_removal.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ident/mem_fit.hpp"
#include "ident/mem_test_data.hpp"
#include "ident/online_mem_estimator.hpp"
#include "models/linear_stage.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;  // [s] the loop's tick

StageModel banning_stage(BanningOrder order = BanningOrder::kHysteresisThenStage) {
  StageModel s;
  s.kind = StageModel::Kind::kSecondOrder;
  s.order = order;
  return s;
}

// Feeds (u_k, y_k) and collects what comes out, then the held sample (reset()).
std::vector<HysteresisSample> run(StageRemoval& removal, const std::vector<double>& u, const std::vector<double>& y) {
  std::vector<HysteresisSample> out;
  HysteresisSample ready[2];
  for (std::size_t k = 0; k < u.size(); ++k) {
    const std::size_t n = removal.feed(u[k], y[k], ready);
    for (std::size_t i = 0; i < n; ++i) out.push_back(ready[i]);
  }
  if (const auto held = removal.reset()) out.push_back(*held);
  return out;
}

// w_k held over tick k drives the exact sampled stage; y_k is the position at the tick's end.
std::vector<double> through_stage(const std::vector<double>& w) {
  SecondOrderStage stage(banning_stage().second_order);
  stage.reset(w.front());
  std::vector<double> y;
  y.reserve(w.size());
  for (const double wk : w) y.push_back(stage.step(wk, kDt));
  return y;
}

std::vector<double> sine(double amplitude, double frequency_hz, std::size_t n) {
  std::vector<double> s(n);
  for (std::size_t k = 0; k < n; ++k)
    s[k] = amplitude * std::sin(2.0 * std::numbers::pi * frequency_hz * kDt * static_cast<double>(k));
  return s;
}

TEST(StageRemoval, WithoutDynamicsPassesTheSamplesThrough) {
  StageRemoval removal(StageModel{}, kDt);
  EXPECT_FALSE(removal.active());
  const std::vector<double> u{1.0, 2.0, 3.0}, y{4e-9, 5e-9, 6e-9};
  const auto out = run(removal, u, y);
  ASSERT_EQ(out.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(out[k].u, u[k]);
    EXPECT_EQ(out[k].y, y[k]);
  }
}

// The stage's lag at 100 Hz (c / k = 17 us) is 5 nm of a 0.5 um sine; what is left after the
// removal (the continuous inverse, moved to the middle of the tick) is third order in the
// frequency: under half a nanometre at every line rate.
TEST(StageRemoval, RecoversTheStagesInputAtLineRates) {
  for (const double f_hz : {10.0, 50.0, 100.0, 200.0}) {
    const double amplitude = 0.5e-6;
    const std::size_t n = static_cast<std::size_t>(0.1 / kDt);
    const auto w = sine(amplitude, f_hz, n);
    const auto y = through_stage(w);
    std::vector<double> u(n);
    for (std::size_t k = 0; k < n; ++k) u[k] = static_cast<double>(k);  // tags each sample
    StageRemoval removal(banning_stage(), kDt);
    const auto out = run(removal, u, y);
    ASSERT_EQ(out.size(), n);
    double worst_raw = 0.0, worst_removed = 0.0;
    for (std::size_t k = 200; k + 1 < n; ++k) {  // past the stage's start-up ring
      EXPECT_EQ(out[k].u, u[k]) << "each output keeps its own tick's input";
      worst_raw = std::max(worst_raw, std::abs(y[k] - w[k]));
      worst_removed = std::max(worst_removed, std::abs(out[k].y - w[k]));
    }
    const double lag_m = amplitude * 2.0 * std::numbers::pi * f_hz * (2.03e3 / 1.17e8);
    EXPECT_GT(worst_raw, 0.8 * lag_m) << f_hz << " Hz: the stage's lag is in the raw samples";
    EXPECT_LT(worst_removed, 0.05 * worst_raw) << f_hz << " Hz";
    EXPECT_LT(worst_removed, 1e-3 * amplitude) << f_hz << " Hz: third order in the frequency, 0.4 nm at 200 Hz";
  }
}

TEST(StageRemoval, HandsOutEachSampleOneTickLateAndTheHeldOneAtABreak) {
  StageRemoval removal(banning_stage(), kDt);
  EXPECT_TRUE(removal.delays());
  HysteresisSample ready[2];
  EXPECT_EQ(removal.feed(1.0, 1e-9, ready), 0u);
  ASSERT_EQ(removal.feed(2.0, 1e-9, ready), 1u);
  EXPECT_EQ(ready[0].u, 1.0);
  EXPECT_DOUBLE_EQ(ready[0].y, 1e-9) << "at rest the stage's input is its position";
  const auto held = removal.reset();
  ASSERT_TRUE(held.has_value());
  EXPECT_EQ(held->u, 2.0);
  EXPECT_EQ(held->y, 1e-9) << "the held sample goes out as measured";
  EXPECT_FALSE(removal.reset().has_value()) << "nothing is held twice";
  EXPECT_EQ(removal.feed(3.0, 2e-9, ready), 0u) << "after a break the next sample is held again";
}

TEST(StageRemoval, ANonFiniteSampleIsABreakAndPassesThrough) {
  StageRemoval removal(banning_stage(), kDt);
  HysteresisSample ready[2];
  removal.feed(1.0, 1e-9, ready);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(removal.feed(nan, nan, ready), 2u);
  EXPECT_EQ(ready[0].u, 1.0);
  EXPECT_TRUE(std::isnan(ready[1].u)) << "the estimator counts it as poison";
  EXPECT_FALSE(removal.reset().has_value());
}

// 1 nm of white sensor noise comes out at sqrt(0.94^2 + 0.71^2 + 0.77^2) = 1.4 nm: the
// differences' weights (the exact inverse's pole at the sampling zero would make it ~70 nm).
TEST(StageRemoval, SensorNoiseStaysBounded) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-9);
  const std::size_t n = 100000;
  std::vector<double> u(n, 0.0), y(n);
  for (double& v : y) v = noise(rng);
  StageRemoval removal(banning_stage(), kDt);
  const auto out = run(removal, u, y);
  double sum2 = 0.0;
  for (const auto& s : out) sum2 += s.y * s.y;
  const double rms = std::sqrt(sum2 / static_cast<double>(out.size()));
  EXPECT_NEAR(rms, 1.41e-9, 0.03e-9);
}

TEST(StageRemoval, StageThenHysteresisGivesTheStagesOutputAsTheInput) {
  const StageModel model = banning_stage(BanningOrder::kStageThenHysteresis);
  StageRemoval removal(model, kDt);
  EXPECT_FALSE(removal.delays());
  const auto u = sine(100.0, 100.0, 500);
  std::vector<double> y(u.size(), 3e-9);
  const auto out = run(removal, u, y);
  ASSERT_EQ(out.size(), u.size());
  SecondOrderStage stage(model.second_order);
  stage.reset(u.front());
  for (std::size_t k = 0; k < u.size(); ++k) {
    EXPECT_DOUBLE_EQ(out[k].u, stage.step(u[k], kDt)) << k;
    EXPECT_EQ(out[k].y, y[k]);
  }
}

TEST(StageRemoval, FeedAllocatesNothing) {
  StageRemoval removal(banning_stage(), kDt);
  HysteresisSample ready[2];
  const testing::AllocationCounter allocations;
  for (int k = 0; k < 1000; ++k) removal.feed(static_cast<double>(k), 1e-9 * k, ready);
  removal.reset();
  EXPECT_EQ(allocations.allocations(), 0u);
}

// What the re-identifier gains: MEM hysteresis then Banning's stage, a 100 Hz loop. Fitted as
// measured, the stage's lag widens the loop and the fit leaves nanometres at the held-out branch;
// fitted after the removal it finds the hysteresis to the noise floor.
TEST(StageRemoval, AFitOfTheRemovedSamplesFindsTheHysteresis) {
  const MemParams truth = testdata::piezo_truth();
  const auto u = testdata::sine_input(100.0, 100.0, 1e4, 0.6);
  const auto w = testdata::mem_branches(u, truth);
  auto y = through_stage(w);
  testdata::add_noise(y, 0.3e-9, 3);
  OnlineMemOptions options;
  options.window_samples = u.size();
  options.capacity_samples = u.size();

  OnlineMemEstimator raw(options, truth);
  for (std::size_t k = 0; k < u.size(); ++k) raw.feed(u[k], y[k]);
  StageRemoval removal(banning_stage(), kDt);
  const auto removed = run(removal, u, y);
  OnlineMemEstimator fitted(options, truth);
  for (const auto& s : removed) fitted.feed(s.u, s.y);

  const MemRefitOutcome as_measured = raw.refit();
  const MemRefitOutcome after_removal = fitted.refit();
  EXPECT_GT(after_removal.holdout_rms_in_use_m, 0.0);
  EXPECT_LT(after_removal.holdout_rms_in_use_m, 0.5 * as_measured.holdout_rms_in_use_m)
      << "the true hysteresis explains the removed samples better than the measured ones";
}

// ---- A linear stage of any order with an input delay ----

StageModel linear_stage(const LinearStageSpec& spec) {
  StageModel s;
  s.kind = StageModel::Kind::kLinear;
  s.linear = spec;
  return s;
}

// The test plant of sim/tracking_experiment.cpp (two_mode_experiment): 1.5 ticks of delay.
LinearStageSpec two_mode() {
  return LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5 * kDt);
}
// A mode that moves the other way first: a right-half-plane zero at +3 kHz, poles at 900 Hz, zeta 0.05.
LinearStageSpec non_minimum_phase() {
  const double zeta = 0.05, f_hz = 900.0;
  return LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-zeta * f_hz, f_hz * std::sqrt(1.0 - zeta * zeta)}});
}
// One mode behind a long delay: 12.3 ticks.
LinearStageSpec long_delay() { return LinearStageSpec::sum_of_modes({{1200.0, 0.04, 1.0}}, 12.3 * kDt); }

std::vector<double> through_linear_stage(const LinearStageSpec& spec, const std::vector<double>& w) {
  LinearStageSimulator stage(discretise(spec, kDt));
  stage.reset(w.front());
  std::vector<double> y;
  y.reserve(w.size());
  for (const double wk : w) y.push_back(stage.step(wk));
  return y;
}

// Power series in x = s dt, to kOrder, computed here from the sampled model's polynomials in
// q = z^-1 = e^{-x} (the removal works from the realisation instead): q^j = sum (-j x)^n / n!.
constexpr int kOrder = 7;
using Series = std::array<double, kOrder + 1>;

Series series_of(const DiscreteLinearStage::Coefficients& c, int skip) {
  Series s{};
  for (Eigen::Index j = skip; j < c.size(); ++j) {
    double term = c(j);  // c_j (-j)^n / n!
    const double jj = static_cast<double>(j - skip);
    for (int n = 0; n <= kOrder; ++n) {
      s[static_cast<std::size_t>(n)] += term;
      term *= -jj / static_cast<double>(n + 1);
    }
  }
  return s;
}
Series product(const Series& a, const Series& b) {
  Series p{};
  for (std::size_t i = 0; i <= static_cast<std::size_t>(kOrder); ++i)
    for (std::size_t j = 0; i + j <= static_cast<std::size_t>(kOrder); ++j) p[i + j] += a[i] * b[j];
  return p;
}
Series quotient(const Series& a, const Series& b) {  // a / b, b[0] != 0
  Series q{};
  for (int n = 0; n <= kOrder; ++n) {
    double r = a[static_cast<std::size_t>(n)];
    for (int j = 1; j <= n; ++j) r -= b[static_cast<std::size_t>(j)] * q[static_cast<std::size_t>(n - j)];
    q[static_cast<std::size_t>(n)] = r / b[0];
  }
  return q;
}

// The stage without its whole ticks of delay, G_r(e^{-x}), normalised to unit DC gain.
Series rational_part(const DiscreteLinearStage& stage) {
  Series g = quotient(series_of(stage.numerator, stage.delay_ticks), series_of(stage.denominator, 0));
  const double dc = g[0];
  for (double& v : g) v /= dc;
  return g;
}

// What the removal leaves of a sine of amplitude 1 at theta = 2 pi f dt: with the whole ticks
// shifted out, the removal is R(x) = 1 + (lead / dt) sinh x + curvature (2 cosh x - 2) (the
// central differences) and the error E(x) = R(x) G_r(x) - 1 = c3 x^3 + c4 x^4 + ...: the Taylor
// remainder of 1 / G_r past its second order, with the differences' own third- and fourth-order
// error. |E(i theta)| <= sum |c_n| theta^n; the series is summed to x^7 and, since the nearest
// singularity of 1 / G_r (its zero nearest DC: the two-mode stage's antiresonance at 1.85 kHz,
// theta = 1.17; the non-minimum-phase zero's theta = 1.88; the sampling zeros at |x| >= pi)
// lies at least 5.8 times further out than 200 Hz (theta = 0.126), the terms beyond x^7 add
// under (1 / 5.8)^8 of the first one: the 10 % margin covers them with room.
double remainder_bound(const DiscreteLinearStage& stage, double lead_s, double curvature, double theta) {
  Series r{};
  r[0] = 1.0;
  double factorial = 1.0;
  for (int n = 1; n <= kOrder; ++n) {
    factorial *= n;
    if (n % 2 == 1) r[static_cast<std::size_t>(n)] += lead_s / kDt / factorial;     // sinh
    if (n % 2 == 0) r[static_cast<std::size_t>(n)] += curvature * 2.0 / factorial;  // 2 cosh - 2
  }
  Series e = product(r, rational_part(stage));
  e[0] -= 1.0;
  EXPECT_LT(std::abs(e[0]) + std::abs(e[1]) + std::abs(e[2]), 1e-9) << "the removal is exact to second order";
  double bound = 0.0, power = theta * theta;
  for (int n = 3; n <= kOrder; ++n) {
    power *= theta;
    bound += std::abs(e[static_cast<std::size_t>(n)]) * power;
  }
  return 1.1 * bound;
}

// The removal's terms are the moments of the sampled model: here from its polynomials in z^-1,
// there from its realisation.
TEST(StageRemoval, ALinearStagesTermsAreItsMoments) {
  for (const LinearStageSpec& spec : {two_mode(), non_minimum_phase(), long_delay()}) {
    const DiscreteLinearStage stage = discretise(spec, kDt);
    const Series inverse = quotient(Series{1.0}, rational_part(stage));  // 1 / G_r = 1 + b1 x + b2 x^2 + ...
    StageRemoval removal(linear_stage(spec), kDt);
    EXPECT_TRUE(removal.delays());
    EXPECT_EQ(removal.delay_samples(), stage.delay_ticks + 1);
    EXPECT_NEAR(removal.lead_s(), inverse[1] * kDt, 1e-9 * kDt);
    EXPECT_NEAR(removal.curvature(), inverse[2], 1e-9 * std::max(1.0, std::abs(inverse[2])));
  }
  EXPECT_EQ(StageRemoval(linear_stage(two_mode()), kDt).delay_samples(), 2) << "1.5 ticks: one whole, shifted out";
  EXPECT_EQ(StageRemoval(linear_stage(long_delay()), kDt).delay_samples(), 13);
}

// Banning's stage: its terms are the moments of its exact sampled model, discretise_zoh()'s
// G(q) = (b1 + b2 q) / (1 + a1 q + a2 q^2) (computed here from the polynomials), as the linear
// stage's removal_terms() of its realisation finds them. The continuous closed form (the inverse
// y + (c/k) y' + y''/k moved half a tick back, less the hold's averaging) is close but not these:
// it integrates the response over continuous time where the samples sum it (0.1 % and 0.6 %).
TEST(StageRemoval, BanningsTermsAreTheMomentsOfItsSampledStage) {
  const SecondOrderStageParams p = banning_stage().second_order;
  const StageRemoval removal(banning_stage(), kDt);
  EXPECT_EQ(removal.delay_samples(), 1);
  const DiscreteStage zoh = discretise_zoh(p, kDt);
  // m1 = G'(1) / G(1), m2 = (G''(1) + G'(1)) / G(1) with G'/G = N'/N - D'/D and
  // G''/G = N''/N - 2 (N'/N)(D'/D) - D''/D + 2 (D'/D)^2.
  const double n0 = zoh.b1 + zoh.b2, n1 = zoh.b2 / n0;
  const double d0 = 1.0 + zoh.a1 + zoh.a2, d1 = (zoh.a1 + 2.0 * zoh.a2) / d0, d2 = 2.0 * zoh.a2 / d0;
  const double m1 = n1 - d1;
  const double m2 = (-2.0 * n1 * d1 - d2 + 2.0 * d1 * d1) + m1;
  EXPECT_NEAR(removal.lead_s(), m1 * kDt, 1e-9 * std::abs(m1 * kDt));
  EXPECT_NEAR(removal.curvature(), m1 * m1 - 0.5 * m2, 1e-9 * std::abs(m1 * m1 - 0.5 * m2));
  const StageRemovalTerms linear = removal_terms(discretise(LinearStageSpec::second_order(p.k, p.c), kDt));
  EXPECT_EQ(linear.delay_ticks, 0);
  EXPECT_NEAR(linear.lead_s, removal.lead_s(), 1e-9 * std::abs(removal.lead_s()));
  EXPECT_NEAR(linear.curvature, removal.curvature(), 1e-9 * std::abs(removal.curvature()));

  const double lag_s = p.c / p.k, h = 0.5 * kDt;
  const double closed_lead_s = lag_s - h;
  const double closed_curvature = (1.0 / p.k - lag_s * h + 0.5 * h * h - kDt * kDt / 24.0) / (kDt * kDt);
  EXPECT_NEAR(removal.lead_s(), closed_lead_s, 2e-3 * std::abs(closed_lead_s));
  EXPECT_NEAR(removal.curvature(), closed_curvature, 1e-2 * closed_curvature);
  EXPECT_GT(std::abs(removal.curvature() - closed_curvature), 1e-3 * closed_curvature) << "not the same terms";
}

// w a sine at line rates through the stage; the recovered w against the true one, d + 1 samples
// late, within the Taylor remainder (remainder_bound) and far inside what the stage does to y.
TEST(StageRemoval, RecoversALinearStagesInputWithinTheTaylorRemainder) {
  struct Case {
    const char* name;
    LinearStageSpec spec;
  };
  for (const Case& c : {Case{"two modes, 1.5 ticks", two_mode()}, Case{"right-half-plane zero", non_minimum_phase()},
                        Case{"one mode, 12.3 ticks", long_delay()}}) {
    const DiscreteLinearStage stage = discretise(c.spec, kDt);
    for (const double f_hz : {10.0, 50.0, 100.0, 200.0}) {
      const double amplitude = 0.5e-6;
      const std::size_t n = static_cast<std::size_t>(0.3 / kDt);
      const auto w = sine(amplitude, f_hz, n);
      const auto y = through_linear_stage(c.spec, w);
      std::vector<double> u(n);
      for (std::size_t k = 0; k < n; ++k) u[k] = static_cast<double>(k);  // tags each sample
      StageRemoval removal(linear_stage(c.spec), kDt);
      const auto out = run(removal, u, y);
      const std::size_t late = static_cast<std::size_t>(removal.delay_samples());
      ASSERT_EQ(out.size(), n - late + 1) << c.name << ": all but the held, and the oldest held at the end";
      double worst_raw = 0.0, worst_removed = 0.0;
      for (std::size_t k = 1500; k + 1 < out.size(); ++k) {  // past the modes' start-up ring (<= 6.8 ms)
        ASSERT_EQ(out[k].u, u[k]) << c.name << ": each output keeps its own tick's input";
        worst_raw = std::max(worst_raw, std::abs(y[k] - w[k]));
        worst_removed = std::max(worst_removed, std::abs(out[k].y - w[k]));
      }
      const double theta = 2.0 * std::numbers::pi * f_hz * kDt;
      const double bound = amplitude * remainder_bound(stage, removal.lead_s(), removal.curvature(), theta);
      EXPECT_LT(worst_removed, bound) << c.name << ", " << f_hz << " Hz";
      EXPECT_LT(bound, 0.02 * worst_raw) << c.name << ", " << f_hz << " Hz: the stage's lag is in the raw samples";
    }
  }
}

TEST(StageRemoval, ALinearStageHandsOutTheOldestHeldSampleAtABreak) {
  StageRemoval removal(linear_stage(long_delay()), kDt);
  ASSERT_EQ(removal.delay_samples(), 13);
  HysteresisSample ready[2];
  for (int k = 0; k < 12; ++k) EXPECT_EQ(removal.feed(k, 1e-9, ready), 0u) << k;
  EXPECT_FALSE(removal.reset().has_value()) << "12 samples: the stage's response to none of them was measured";
  for (int k = 0; k < 13; ++k) EXPECT_EQ(removal.feed(k, 1e-9 * k, ready), 0u) << k;
  ASSERT_EQ(removal.feed(13.0, 13e-9, ready), 1u);
  EXPECT_EQ(ready[0].u, 0.0);
  EXPECT_NEAR(ready[0].y, 12e-9 + removal.lead_s() * 1e-9 / kDt, 1e-22)
      << "the position 12 ticks on and its slope (a ramp: no curvature)";
  for (int k = 14; k < 40; ++k) ASSERT_EQ(removal.feed(k, 1e-9 * k, ready), 1u) << k;
  EXPECT_EQ(ready[0].u, 26.0);
  const auto held = removal.reset();
  ASSERT_TRUE(held.has_value());
  EXPECT_EQ(held->u, 27.0) << "the oldest of the 13 held";
  EXPECT_EQ(held->y, 1e-9 * 39) << "with the last position as measured, 12 ticks on";
  EXPECT_FALSE(removal.reset().has_value()) << "the 12 younger ones are dropped, nothing is held twice";
  for (int k = 0; k < 13; ++k) EXPECT_EQ(removal.feed(k, 1e-9, ready), 0u) << k << ": held again after a break";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(removal.feed(nan, nan, ready), 2u) << "a non-finite sample is a break: the oldest held, then itself";
  EXPECT_EQ(ready[0].u, 0.0);
  EXPECT_TRUE(std::isnan(ready[1].y));
}

TEST(StageRemoval, ALinearStagesFeedAndResetAllocateNothing) {
  StageRemoval removal(linear_stage(long_delay()), kDt);
  HysteresisSample ready[2];
  std::size_t out = 0;
  const testing::AllocationCounter allocations;
  for (int k = 0; k < 1000; ++k) {
    out += removal.feed(static_cast<double>(k), 1e-9 * k, ready);
    if (k % 100 == 99) out += removal.reset().has_value() ? 1 : 0;
  }
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_EQ(out, 10u * (100u - 13u + 1u));
}

// Behind the two-mode stage (1.5 ticks of delay, its modes' lag: 0.5 degree at 10 Hz), a fit of
// u -> y reads the stage as hysteresis: a wider loop. Fitted on the removed samples it finds the
// hysteresis itself: its branches are closer to the true ones, on the loop it was fitted on.
TEST(StageRemoval, AFitBehindALinearStageFindsTheHysteresisAfterTheRemoval) {
  const MemParams truth = testdata::piezo_truth();
  for (const double f_hz : {10.0, 100.0}) {
    const auto u = testdata::sine_input(160.0, f_hz, 1e4, f_hz < 50.0 ? 1.0 : 0.3);
    const auto w = testdata::mem_branches(u, truth);
    auto y = through_linear_stage(two_mode(), w);
    testdata::add_noise(y, 1e-9, 3);
    StageRemoval removal(linear_stage(two_mode()), kDt);
    const auto removed = run(removal, u, y);
    std::vector<double> u_removed, y_removed;
    for (const auto& s : removed) {
      u_removed.push_back(s.u);
      y_removed.push_back(s.y);
    }
    const MemFitResult as_measured = fit_mem(u, y);
    const MemFitResult after_removal = fit_mem(u_removed, y_removed);
    ASSERT_TRUE(as_measured.ok()) << f_hz << " Hz";
    ASSERT_TRUE(after_removal.ok()) << f_hz << " Hz";
    // Each fit's branches against the true ones, each up to its best constant offset (a fit does not
    // know the loop's centre).
    auto distance = [&](const MemParams& p) {
      const auto fitted = testdata::mem_branches(u, p);
      double mean = 0.0;
      for (std::size_t k = 0; k < u.size(); ++k) mean += fitted[k] - w[k];
      mean /= static_cast<double>(u.size());
      double ss = 0.0;
      for (std::size_t k = 0; k < u.size(); ++k) ss += (fitted[k] - w[k] - mean) * (fitted[k] - w[k] - mean);
      return std::sqrt(ss / static_cast<double>(u.size()));
    };
    const double raw_m = distance(as_measured.params), removed_m = distance(after_removal.params);
    EXPECT_LT(removed_m, 0.5 * raw_m) << f_hz << " Hz: " << removed_m * 1e9 << " nm against " << raw_m * 1e9 << " nm";
    EXPECT_LT(testdata::rel_err(after_removal.params.c1, truth.c1), testdata::rel_err(as_measured.params.c1, truth.c1))
        << f_hz << " Hz";
  }
}

}  // namespace
}  // namespace hystloop
