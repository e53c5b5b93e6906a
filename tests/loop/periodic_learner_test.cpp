// The learner's own rules, driven tick by tick: the filter Q as built (its taps, zero phase, the
// wrap over the period, the clamp), the two updates' arithmetic through a lag, which periods are
// learned from and which are skipped, idle and disabled states, no allocation on the per-sample
// calls, validation. The closed loop (convergence, noise, lag, restarts, wrong models) is
// periodic_learner_loop_test.cpp, the lag-compensated update's stability periodic_learner_lag_test.cpp.
#include "loop/periodic_learner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "periodic_learner_rig.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using testing::kLearnDt;

constexpr double kNm = 1e-9;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Plans tick k with reference 0 and observes y at once; returns the correction planned.
double tick(PeriodicLearner& l, std::int64_t k, double y) {
  const double c = l.correction(k, 0.0);
  l.observe(k, y);
  return c;
}

TEST(PeriodicLearner, FilterIsTheTriangleNearestBelowTheCutoff) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 0);
  EXPECT_EQ(l.filter_half_width(), 4);  // 1 kHz at 10 kHz
  EXPECT_NEAR(l.filter_cutoff_hz(), 1138.5, 0.1);
  EXPECT_DOUBLE_EQ(l.filter_null_hz(), 2500.0);
  EXPECT_DOUBLE_EQ(l.filter_norm_sq(), 33.0 / 192.0);
  // Its -6 dB is where the response says, and the next longer window would be below the cutoff.
  EXPECT_NEAR(testing::triangle_response(l.filter_cutoff_hz() * kLearnDt, 4), 0.5, 1e-9);
  EXPECT_LT(testing::triangle_response(1000.0 * kLearnDt, 5), 0.5);
  LearningConfig c;
  c.cutoff_hz = 500.0;
  PeriodicLearner slower(c, kLearnDt, 0);
  EXPECT_EQ(slower.filter_half_width(), 8);
  EXPECT_GE(slower.filter_cutoff_hz(), 500.0);
  EXPECT_LT(testing::triangle_response(500.0 * kLearnDt, 9), 0.5);
  c.cutoff_hz = 2500.0;  // fs/4: the shortest window there is
  EXPECT_EQ(PeriodicLearner(c, kLearnDt, 0).filter_half_width(), 2);
}

// One error sample at phase 1 of a 20-tick period: the next period's correction is gain x the
// triangle centred on it (zero phase: symmetric, nothing delayed), wrapped over the period's end.
TEST(PeriodicLearner, AnErrorImpulseLearnsTheSymmetricWindowAroundIt) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 0);
  l.restart(0, 20);
  const double delta = 16 * kNm;
  for (std::int64_t k = 0; k < 20; ++k) EXPECT_EQ(tick(l, k, k == 1 ? -delta : 0.0), 0.0);
  EXPECT_EQ(l.figures().periods_learned, 1u);
  EXPECT_NEAR(l.figures().last_error_max_m, delta, 1e-18);
  EXPECT_NEAR(l.figures().last_error_rms_m, delta / std::sqrt(20.0), 1e-18);
  std::vector<double> c(20);
  for (std::int64_t i = 0; i < 20; ++i) c[static_cast<std::size_t>(i)] = l.correction(20 + i, 0.0);
  const double g = l.gain();
  const double expected[7] = {1, 2, 3, 4, 3, 2, 1};  // phases 18, 19, 0, 1, 2, 3, 4
  for (int j = -3; j <= 3; ++j) {
    const auto phase = static_cast<std::size_t>((1 + j + 20) % 20);
    EXPECT_NEAR(c[phase], g * delta * expected[j + 3] / 16.0, 1e-20) << "phase " << phase;
  }
  double sum = 0.0;
  // Outside the window only the running sums' rounding (1e-25 m) is left.
  for (std::size_t i = 5; i < 18; ++i) EXPECT_NEAR(c[i], 0.0, 1e-20);
  for (const double v : c) sum += v;
  EXPECT_NEAR(sum, g * delta, 1e-20);  // Q(0) = 1: the mean is kept
  EXPECT_EQ(l.figures().tables_adopted, 1u);
  EXPECT_NEAR(l.figures().correction_rms_m, std::sqrt((2 * 1 + 2 * 4 + 2 * 9 + 16) / 20.0) * g * delta / 16.0, 1e-20);
}

// A tick the plan held back (a limit cut what its correction asked) is not learned from: its
// error would only grow the table there period after period. The same impulse as above, held,
// leaves the next table at zero; the figures count the tick once, however often it is held.
TEST(PeriodicLearner, AHeldTickIsNotLearnedFrom) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 0);
  l.restart(0, 20);
  const double delta = 16 * kNm;
  for (std::int64_t k = 0; k < 20; ++k) {
    EXPECT_EQ(l.correction(k, 0.0), 0.0);
    if (k == 1) {
      l.hold(1);
      l.hold(1);
      l.hold(0);  // planned over (the ring holds one tick here): not the slot's tick, ignored
    }
    l.observe(k, k == 1 ? -delta : 0.0);
  }
  EXPECT_EQ(l.figures().periods_learned, 1u);
  EXPECT_NEAR(l.figures().last_error_max_m, delta, 1e-18);  // the error is still reported
  EXPECT_EQ(l.figures().ticks_held, 1u);
  for (std::int64_t i = 0; i < 20; ++i) EXPECT_EQ(l.correction(20 + i, 0.0), 0.0) << i;
}

// A constant error (y = delta, r = 0) seen 40 ticks late on 20-tick periods: period p's table is
// adopted at period p + 3 (L = 3). Q keeps a constant, so each table is one number, and the one
// in use in period q is exactly what the update's recursion gives:
//   plain:            c_p = c_applied(p) - gain delta
//   lag-compensated:  c_p = (1 - gain) c_{p-1} + gain (c_applied(p) - delta),   c_applied(p) = c_{p-3}.
TEST(PeriodicLearner, EachUpdateLearnsThroughTheLagAsItsRecursionSays) {
  constexpr std::int64_t n = 20, ahead = 40, chain = 3, periods = 12;
  const double delta = 8 * kNm;
  double in_period_4[2] = {0.0, 0.0};  // lag-compensated, plain
  for (const bool lag_compensated : {true, false}) {
    LearningConfig config = testing::stepwise();
    config.lag_compensated = lag_compensated;
    PeriodicLearner l(config, kLearnDt, ahead + 5);
    EXPECT_EQ(l.lag_compensated(), lag_compensated);
    l.restart(0, n);
    const double g = l.gain();
    std::vector<double> table(periods, 0.0);  // c_p, the recursion's
    for (std::int64_t p = 0; p < periods; ++p) {
      const double applied = p >= chain ? table[static_cast<std::size_t>(p - chain)] : 0.0;
      const double newest = p >= 1 ? table[static_cast<std::size_t>(p - 1)] : 0.0;
      table[static_cast<std::size_t>(p)] =
          lag_compensated ? (1.0 - g) * newest + g * (applied - delta) : applied - g * delta;
    }
    for (std::int64_t k = 0; k < ahead; ++k) EXPECT_EQ(l.correction(k, 0.0), 0.0);
    for (std::int64_t k = 0; k + ahead < periods * n; ++k) {
      const std::int64_t planned = k + ahead;
      const double c = l.correction(planned, 0.0);
      const std::int64_t q = planned / n;
      const double expected = q >= chain ? table[static_cast<std::size_t>(q - chain)] : 0.0;
      ASSERT_NEAR(c, expected, 1e-24) << (lag_compensated ? "lag-compensated" : "plain") << ", tick " << planned;
      if (planned == 4 * n) in_period_4[lag_compensated ? 0 : 1] = c;
      l.observe(k, delta);
    }
    EXPECT_EQ(l.figures().tables_adopted, static_cast<std::uint64_t>(periods - chain));
  }
  // The updates part from c_1 on (in use in period 4): the plain one learns c_1 = c_0, the
  // lag-compensated one builds on c_0 although c_0 was not applied yet.
  EXPECT_NEAR(in_period_4[0], -0.5 * kNm * 8 * (2.0 - 0.5), 1e-24);
  EXPECT_NEAR(in_period_4[1], -0.5 * kNm * 8, 1e-24);
}

// Two periods observed before the plan reaches a boundary (samples arriving in a batch): the
// second table builds on the first, still waiting (the newest table, not the one in use), and
// replaces it; only the second is adopted.
TEST(PeriodicLearner, ATableLearnedWhileAnotherWaitsBuildsOnTheWaitingOne) {
  constexpr std::int64_t n = 20;
  const double delta = 8 * kNm;
  for (const bool lag_compensated : {true, false}) {
    LearningConfig config = testing::stepwise();
    config.lag_compensated = lag_compensated;
    PeriodicLearner l(config, kLearnDt, 5 * n);
    l.restart(0, n);
    for (std::int64_t k = 0; k < 5 * n; ++k) ASSERT_EQ(l.correction(k, 0.0), 0.0);
    for (std::int64_t k = 0; k < 2 * n; ++k) l.observe(k, delta);
    EXPECT_EQ(l.figures().periods_learned, 2u);
    EXPECT_EQ(l.figures().tables_adopted, 0u);
    const double g = l.gain();
    // Lag-compensated: c_1 = (1 - gain) c_0 + gain (0 - delta) with c_0 = -gain delta; plain: c_1 = -gain delta.
    const double expected = lag_compensated ? -g * delta * (2.0 - g) : -g * delta;
    EXPECT_NEAR(l.correction(5 * n, 0.0), expected, 1e-24);
    EXPECT_EQ(l.figures().tables_adopted, 1u);
  }
}

// Without lag (the table from period p in use in p + 1, D = 0) the newest table is the one
// applied, and the two updates are one: the same tables in the same closed loop.
TEST(PeriodicLearner, WithoutLagBothUpdatesAreTheSame) {
  constexpr std::int64_t n = 100, periods = 30;
  std::vector<double> corr[2];
  for (const bool lag_compensated : {true, false}) {
    LearningConfig config = testing::stepwise();
    config.lag_compensated = lag_compensated;
    PeriodicLearner learner(config, kLearnDt, 0);
    testing::LearningLoop loop(
        learner, periods * n, {0.8, 1}, [](std::int64_t k) { return testing::raster(k, n, 300 * kNm); },
        [](std::int64_t k) { return testing::disturbance(k, n); }, 1e-9, 5);
    loop.horizon = 0;
    loop.block = 1;
    learner.restart(0, n);
    loop.run(periods * n);
    EXPECT_EQ(loop.first_adoption_period(n), 1);
    EXPECT_EQ(learner.figures().tables_adopted, static_cast<std::uint64_t>(periods - 1));
    corr[lag_compensated ? 0 : 1] = loop.corr;
  }
  double largest = 0.0;
  for (std::size_t k = 0; k < corr[0].size(); ++k) {
    ASSERT_NEAR(corr[0][k], corr[1][k], 1e-20) << "tick " << k;  // the update's rounding differs, 1e-24 m
    largest = std::max(largest, std::abs(corr[0][k]));
  }
  EXPECT_GT(largest, 50 * kNm);
}

// A new table takes over from the one in use along a linear blend of blend_s from the boundary
// (5 ms, 50 ticks, by default; never longer than the period): the first table of a constant
// error, c0 = -gain delta everywhere, enters as c0 (j + 1) / 50 at tick j of its first period, and
// the largest tick-to-tick change of the correction is |c0| / 50 where without the blend it is
// the whole step |c0|, which the stage's inverse would turn into a ringing at half the tick rate.
TEST(PeriodicLearner, ANewTableTakesOverAlongTheBlend) {
  const double delta = 10 * kNm;
  for (const std::int64_t n : {200, 20}) {
    for (const bool blended : {true, false}) {
      LearningConfig config;  // the deployed blend, without the ramp (tested below)
      config.ramp_periods = 0.0;
      if (!blended) config.blend_s = 0.0;
      PeriodicLearner l(config, kLearnDt, 0);
      EXPECT_EQ(l.blend_ticks(), blended ? 50 : 0);
      l.restart(0, n);
      for (std::int64_t k = 0; k < n; ++k) ASSERT_EQ(tick(l, k, delta), 0.0);
      const double c0 = -l.gain() * delta;
      const std::int64_t over = blended ? std::min<std::int64_t>(50, n) : 1;
      double previous = 0.0, largest_step = 0.0;
      for (std::int64_t j = 0; j < n; ++j) {
        const double c = l.correction(n + j, 0.0);
        const double expected = c0 * static_cast<double>(std::min(j + 1, over)) / static_cast<double>(over);
        ASSERT_NEAR(c, expected, 1e-22) << "period " << n << ", tick " << j << (blended ? ", blended" : ", stepwise");
        largest_step = std::max(largest_step, std::abs(c - previous));
        previous = c;
      }
      EXPECT_NEAR(largest_step, std::abs(c0) / static_cast<double>(over), 1e-22);
    }
  }
}

// A line's first table comes in along the ramp, one ramp_periods-th of it per period, and a stop
// part way up fades out from what was applied, not from the whole table.
TEST(PeriodicLearner, ALinesFirstTablesComeInAlongTheRamp) {
  const double delta = 10 * kNm;
  const std::int64_t n = 20;
  LearningConfig config = testing::stepwise();
  config.ramp_periods = 4.0;
  EXPECT_EQ(LearningConfig{}.ramp_periods, 4.0);  // the deployed one
  PeriodicLearner l(config, kLearnDt, 0);
  l.restart(0, n);
  for (std::int64_t k = 0; k < n; ++k) ASSERT_EQ(tick(l, k, delta), 0.0);
  const double c0 = -l.gain() * delta;  // the first table (no more samples: it stays in use)
  const std::int64_t ramp = 4 * n;
  for (std::int64_t j = 0; j < ramp + n; ++j) {
    const double expected = c0 * static_cast<double>(std::min(j + 1, ramp)) / static_cast<double>(ramp);
    ASSERT_NEAR(l.correction(n + j, 0.0), expected, 1e-22) << "tick " << j << " of the ramp";
  }

  // Stopped half way up: the fade starts at what the ramp applied and never steps.
  PeriodicLearner m(config, kLearnDt, 0);
  m.restart(0, n);
  for (std::int64_t k = 0; k < n; ++k) tick(m, k, delta);
  double previous = 0.0;
  std::int64_t k = n;
  for (; k < n + ramp / 2; ++k) previous = m.correction(k, 0.0);
  EXPECT_NEAR(previous, c0 / 2.0, 1e-22);
  m.stop();
  double largest_step = 0.0;
  for (std::int64_t j = 0; j < m.fade_ticks() + 1; ++j, ++k) {
    const double c = m.correction(k, 0.0);
    largest_step = std::max(largest_step, std::abs(c - previous));
    previous = c;
  }
  EXPECT_EQ(previous, 0.0);
  EXPECT_NEAR(largest_step, std::abs(c0) / 2.0 / static_cast<double>(m.fade_ticks()), 1e-22);
}

TEST(PeriodicLearner, TheTableIsClampedToTheBound) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 0);
  l.restart(0, 20);
  for (std::int64_t k = 0; k < 20; ++k) tick(l, k, k == 5 ? -10e-6 : 0.0);
  double largest = 0.0;
  for (std::int64_t k = 20; k < 40; ++k) largest = std::max(largest, std::abs(l.correction(k, 0.0)));
  EXPECT_DOUBLE_EQ(largest, LearningConfig{}.max_correction_m);
}

// A period with a hole (a tick not delivered, NaN, a sample later than max_lag_ticks, periods
// without any sample) is not learned from: the table from period 0 stays until period 6's.
TEST(PeriodicLearner, APeriodWithAMissingSampleIsSkipped) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 5);
  l.restart(0, 20);
  const double delta = 16 * kNm;
  for (std::int64_t k = 0; k < 20; ++k) tick(l, k, k == 1 ? -delta : 0.0);
  const double learned = l.correction(20, 0.0);
  EXPECT_NE(learned, 0.0);
  for (std::int64_t k = 20; k < 40; ++k) {
    if (k > 20) l.correction(k, 0.0);
    if (k != 25) l.observe(k, 0.0);  // 25 never arrives
  }
  for (std::int64_t k = 40; k < 60; ++k) tick(l, k, k == 45 ? kNaN : 0.0);
  for (std::int64_t k = 60; k < 68; ++k) l.correction(k, 0.0);  // 60 and 61 are planned over
  for (std::int64_t k = 60; k < 68; ++k) l.observe(k, 0.0);
  for (std::int64_t k = 68; k < 80; ++k) tick(l, k, 0.0);
  EXPECT_EQ(l.figures().periods_skipped, 3u);
  for (std::int64_t k = 80; k < 120; ++k) l.correction(k, 0.0);  // periods 4 and 5: no samples at all
  EXPECT_EQ(l.correction(120, 0.0), learned);                    // still the table from period 0
  l.observe(120, 0.0);
  EXPECT_EQ(l.figures().periods_skipped, 5u);
  for (std::int64_t k = 121; k < 140; ++k) tick(l, k, 0.0);
  EXPECT_EQ(l.figures().periods_learned, 2u);
  EXPECT_EQ(l.figures().periods_completed, 7u);
  EXPECT_EQ(l.figures().tables_adopted, 1u);
  // Period 6 saw no error: the next table (adopted at 140) is Q of the one it applied, smoother.
  EXPECT_LT(std::abs(l.correction(140, 0.0)), std::abs(learned));
  EXPECT_EQ(l.figures().tables_adopted, 2u);
}

TEST(PeriodicLearner, IdleForPeriodsItCannotLearnAndBeforeK0) {
  PeriodicLearner l(testing::stepwise(), kLearnDt, 0);
  EXPECT_FALSE(l.figures().active);
  for (const std::int64_t n : {std::int64_t{1}, std::int64_t{0}, l.max_period_ticks() + 1}) {
    l.restart(0, n);
    EXPECT_FALSE(l.figures().active) << n;
    EXPECT_EQ(l.figures().period_ticks, 0);
    for (std::int64_t k = 0; k < 200; ++k) ASSERT_EQ(tick(l, k, 1e-6), 0.0);
    EXPECT_EQ(l.figures().periods_completed, 0u);
  }
  // Phase 0 at tick 300: nothing before it is learned from, then the first period is.
  l.restart(300, l.max_period_ticks());
  EXPECT_TRUE(l.figures().active);
  for (std::int64_t k = 200; k < 300; ++k) ASSERT_EQ(tick(l, k, 1e-6), 0.0);
  EXPECT_EQ(l.figures().periods_completed, 0u);
  l.restart(300, 20);
  for (std::int64_t k = 300; k < 320; ++k) tick(l, k, -1 * kNm);
  EXPECT_EQ(l.figures().periods_learned, 1u);
  EXPECT_NEAR(l.correction(320, 0.0), l.gain() * kNm, 1e-20);
}

TEST(PeriodicLearner, DisabledByConfigLearnsOnlyWhenTurnedOn) {
  LearningConfig c = testing::stepwise();
  c.enabled = false;
  PeriodicLearner l(c, kLearnDt, 0);
  l.restart(0, 20);
  EXPECT_FALSE(l.figures().active);
  EXPECT_EQ(l.figures().period_ticks, 20);
  for (std::int64_t k = 0; k < 40; ++k) ASSERT_EQ(tick(l, k, -1 * kNm), 0.0);
  l.set_enabled(true);  // at tick 40: learns from the next period boundary on
  EXPECT_TRUE(l.figures().active);
  for (std::int64_t k = 40; k < 60; ++k) ASSERT_EQ(tick(l, k, -1 * kNm), 0.0);
  EXPECT_NEAR(l.correction(60, 0.0), l.gain() * kNm, 1e-20);
}

// Every per-sample call and every state change, in the closed loop, in either update: no allocation.
TEST(PeriodicLearner, PerSampleCallsAndStateChangesAllocateNothing) {
  constexpr std::int64_t n = 300;
  for (const bool lag_compensated : {true, false}) {
    LearningConfig config;  // the deployed one: its blends too
    config.lag_compensated = lag_compensated;
    PeriodicLearner learner(config, kLearnDt, testing::kMaxLag);
    testing::LearningLoop loop(
        learner, 60 * n, {0.9, 1}, [](std::int64_t k) { return 1e-7 * std::sin(0.02 * static_cast<double>(k)); },
        [](std::int64_t k) { return 1e-8 * std::cos(0.06 * static_cast<double>(k)); }, 1e-9, 21);
    loop.drop = [](std::int64_t k) { return k % 4999 == 0; };
    learner.restart(0, n);
    testing::AllocationCounter counter;
    loop.run(15 * n);
    learner.reset();
    loop.run(10 * n);
    learner.restart(loop.planned + 1, n / 2);
    loop.run(10 * n);
    learner.set_enabled(false);
    loop.run(5 * n);
    learner.set_enabled(true);
    loop.run(10 * n);
    learner.stop();
    loop.run(5 * n);
    EXPECT_EQ(counter.allocations(), 0u);
    EXPECT_GT(learner.figures().periods_learned, 30u);
    EXPECT_GT(learner.figures().periods_skipped, 0u);
  }
}

TEST(PeriodicLearner, LagCompensatedByDefault) {
  EXPECT_TRUE(LearningConfig{}.lag_compensated);
  EXPECT_TRUE(PeriodicLearner({}, kLearnDt, 0).lag_compensated());
}

TEST(PeriodicLearner, ValidationNamesTheField) {
  using testing::refused_field;
  auto with = [](auto change) {
    LearningConfig c;
    change(c);
    return [c] { PeriodicLearner l(c, kLearnDt, 500); };
  };
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.gain = 0.0; })), "learning.gain");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.gain = 1.5; })), "learning.gain");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.gain = kNaN; })), "learning.gain");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.cutoff_hz = 0.0; })), "learning.cutoff_hz");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.cutoff_hz = 3000.0; })), "learning.cutoff_hz");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.max_correction_m = 0.0; })), "learning.max_correction_m");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.max_correction_m = 1e-3; })), "learning.max_correction_m");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.max_period_s = 1e-4; })), "learning.max_period_s");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.max_period_s = 60.0; })), "learning.max_period_s");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.fade_s = 0.0; })), "learning.fade_s");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.blend_s = -1e-3; })), "learning.blend_s");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.ramp_periods = -1.0; })), "learning.ramp_periods");
  EXPECT_EQ(refused_field(with([](LearningConfig& c) { c.ramp_periods = kNaN; })), "learning.ramp_periods");
  EXPECT_EQ(refused_field([] { PeriodicLearner l({}, 0.0, 500); }), "compensator.dt_s");
  EXPECT_EQ(refused_field([] { PeriodicLearner l(testing::stepwise(), kLearnDt, -1); }), "learning.max_lag_ticks");
  try {
    LearningConfig c;
    c.gain = 2.0;
    c.validate(kLearnDt);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("learning.gain: must be in [0, 1] (got 2)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hystloop
