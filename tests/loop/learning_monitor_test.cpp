// The learning's monitor (loop/periodic_learner.hpp): a line whose learning makes its error worse
// than without learning is stopped, falls back to its best period's corrections (or none), and is
// counted; a line that converges is never stopped. Driven by the closed loop of
// periodic_learner_rig.hpp, a horizon late, with plants the update cannot learn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "loop/periodic_learner.hpp"
#include "periodic_learner_rig.hpp"

namespace hystloop {
namespace {

using testing::disturbance;
using testing::kLearnDt;
using testing::LearningLoop;
using testing::LinearPlant;
using testing::raster;

constexpr double kNm = 1e-9;
constexpr double kSigma = 1e-9;
constexpr std::int64_t kPeriod = 200;
constexpr std::int64_t kPeriods = 60;
constexpr double kRatio = 1.05;  // what deploy/config/two-mode sets

struct LearningRun {
  double off_rms = 0.0;    // period 1: no table yet
  double worst_rms = 0.0;  // the worst period from 2 on
  double last_rms = 0.0;   // the last period
  LearnerFigures figures;
};

LearningRun run_learning(const LinearPlant& plant, double monitor_ratio, double amplitude_m = 100 * kNm) {
  LearningConfig config;  // the deployed one: blends and fades included
  config.monitor_ratio = monitor_ratio;
  PeriodicLearner learner(config, kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, kPeriods * kPeriod, plant, [=](std::int64_t k) { return raster(k, kPeriod, amplitude_m); },
      [](std::int64_t k) { return disturbance(k, kPeriod); }, kSigma, 5);
  learner.restart(0, kPeriod);
  loop.run(kPeriods * kPeriod);
  LearningRun r;
  r.off_rms = loop.error_rms(kPeriod, 2 * kPeriod);
  for (std::int64_t p = 2; p < kPeriods; ++p) {
    r.worst_rms = std::max(r.worst_rms, loop.error_rms(p * kPeriod, (p + 1) * kPeriod));
  }
  r.last_rms = loop.error_rms((kPeriods - 1) * kPeriod, kPeriods * kPeriod);
  r.figures = learner.figures();
  return r;
}

// Plants the update cannot learn (the model's sign wrong, eight ticks of delay left out, a gain
// far off): without the monitor the error grows past the learning-off error; with it the line's
// learning is stopped, counted and shown, and no period is much worse than without learning.
TEST(LearningMonitor, StopsALineWhoseLearningMakesTheErrorWorse) {
  for (const LinearPlant& plant : {LinearPlant{-1.0, 0}, LinearPlant{1.0, 8}, LinearPlant{3.2, 0}}) {
    const LearningRun unguarded = run_learning(plant, 0.0);
    const LearningRun guarded = run_learning(plant, kRatio);
    std::printf(
        "gain %.1f, delay %lld: off %.2f nm; unguarded worst %.2f nm, last %.2f; guarded worst %.2f, last %.2f\n",
        plant.gain, static_cast<long long>(plant.delay), guarded.off_rms / kNm, unguarded.worst_rms / kNm,
        unguarded.last_rms / kNm, guarded.worst_rms / kNm, guarded.last_rms / kNm);
    EXPECT_GT(unguarded.worst_rms, 1.3 * unguarded.off_rms) << "the plant must be one learning cannot learn";
    EXPECT_EQ(guarded.figures.divergences, 1U);
    EXPECT_TRUE(guarded.figures.diverged);
    EXPECT_FALSE(guarded.figures.active);
    EXPECT_LE(guarded.last_rms, 1.1 * guarded.off_rms);
    EXPECT_LT(guarded.worst_rms, unguarded.worst_rms);
  }
}

// Plants the update learns (the model a gain 0.5 or 1.5 off, three ticks of delay): the monitor
// never stops them, and the learned error is what it was without the monitor.
TEST(LearningMonitor, LeavesALineThatConvergesAlone) {
  for (const LinearPlant& plant :
       {LinearPlant{1.0, 0}, LinearPlant{0.5, 0}, LinearPlant{1.5, 0}, LinearPlant{1.0, 3}}) {
    const LearningRun guarded = run_learning(plant, kRatio);
    const LearningRun unguarded = run_learning(plant, 0.0);
    EXPECT_EQ(guarded.figures.divergences, 0U) << plant.gain << " " << plant.delay;
    EXPECT_FALSE(guarded.figures.diverged);
    EXPECT_DOUBLE_EQ(guarded.last_rms, unguarded.last_rms);
    EXPECT_LT(guarded.last_rms, 0.5 * guarded.off_rms);
    EXPECT_GT(guarded.figures.baseline_rms_m, 0.0);
  }
}

// A line whose error is the sensor's noise alone (a perfect model) is never stopped: the learned
// noise raises its RMS by a few percent and a period's RMS of noise scatters by ~1/sqrt(2n) (7 %
// at n = 100), which the monitor's margin and its second period leave to a growing error. Three
// hundred 100-tick periods, ten seeds: a rule of one period above 1.05 times the first stops it.
TEST(LearningMonitor, NeverStopsALineOfNoiseAlone) {
  constexpr std::int64_t kShort = 100;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    PeriodicLearner learner(LearningConfig{}, kLearnDt, testing::kMaxLag);
    ASSERT_EQ(LearningConfig{}.monitor_ratio, kRatio);  // on by default
    LearningLoop loop(
        learner, 300 * kShort, LinearPlant{1.0, 0}, [](std::int64_t) { return 0.0; }, [](std::int64_t) { return 0.0; },
        kSigma, seed);
    learner.restart(0, kShort);
    loop.run(300 * kShort);
    EXPECT_EQ(learner.figures().divergences, 0U)
        << "seed " << seed << " baseline " << learner.figures().baseline_rms_m << " last "
        << learner.figures().last_error_rms_m << " periods " << learner.figures().periods_learned;
    EXPECT_GT(learner.figures().periods_learned, 250U);
  }
}

// A parameter set swapped in under a converged table steps the repeating error (here by a third
// harmonic of 60 nm, twice the baseline's RMS) for the lag and a few periods while the tables learn
// it: told of the swap, the monitor does not take that for a divergence; not told, it does.
TEST(LearningMonitor, ASwapsStepOfTheErrorIsNotADivergence) {
  constexpr std::int64_t kSwap = 40 * kPeriod;
  for (const bool told : {true, false}) {
    PeriodicLearner learner(LearningConfig{}, kLearnDt, testing::kMaxLag);
    LearningLoop loop(
        learner, kPeriods * kPeriod, LinearPlant{1.0, 0}, [](std::int64_t k) { return raster(k, kPeriod, 100 * kNm); },
        [](std::int64_t k) {
          const double step =
              k >= kSwap ? 60e-9 * std::sin(2.0 * std::numbers::pi * 3.0 * static_cast<double>(k) / kPeriod + 0.3)
                         : 0.0;
          return disturbance(k, kPeriod) + step;
        },
        kSigma, 3);
    learner.restart(0, kPeriod);
    loop.run(kSwap - testing::kHorizon);  // planned up to the swap
    if (told) learner.params_swapped(kSwap);
    loop.run(kPeriods * kPeriod - loop.now);
    EXPECT_EQ(learner.figures().divergences, told ? 0U : 1U) << (told ? "told" : "not told");
    if (told) {
      EXPECT_LT(loop.error_rms((kPeriods - 1) * kPeriod, kPeriods * kPeriod), 3 * kNm);
    }
  }
}

// A restart (a new line) learns again after the monitor stopped the last one.
TEST(LearningMonitor, ANewLineLearnsAgain) {
  LearningConfig config;
  config.monitor_ratio = kRatio;
  PeriodicLearner learner(config, kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, 2 * kPeriods * kPeriod, LinearPlant{-1.0, 0},
      [](std::int64_t k) { return raster(k, kPeriod, 100 * kNm); },
      [](std::int64_t k) { return disturbance(k, kPeriod); }, kSigma, 9);
  learner.restart(0, kPeriod);
  loop.run(kPeriods * kPeriod);
  ASSERT_TRUE(learner.figures().diverged);
  learner.restart(loop.now + testing::kHorizon + kPeriod, kPeriod);
  loop.run(2 * kPeriod);  // the table held fades out, then the new line learns
  EXPECT_FALSE(learner.figures().diverged);
  EXPECT_TRUE(learner.figures().active);
  EXPECT_EQ(learner.figures().divergences, 1U);  // counted, not forgotten
}

}  // namespace
}  // namespace hystloop
