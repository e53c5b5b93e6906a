// Taking the stage out of measured samples: the hysteresis' output recovered from the stage's
// position, one sample late; breaks hand out the held sample; a fit on the removed samples finds
// the hysteresis that a fit of u -> y blurs with the stage's lag.
#include "ident/stage_removal.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ident/mem_test_data.hpp"
#include "ident/online_mem_estimator.hpp"
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

}  // namespace
}  // namespace hystloop
