#include "loop/experiment_queue.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/errors.hpp"
#include "loop/experiment.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

ExperimentSpec sine(double amplitude_V, double frequency_hz, double duration_s, double offset_V = 0.0) {
  return make_experiment_spec("sine", amplitude_V, offset_V, frequency_hz, duration_s);
}

double voltage_at(const ExperimentSpec& s, double since_start_s) {
  return s.offset_V + s.amplitude_V * std::sin(2.0 * std::numbers::pi * s.frequency_hz * since_start_s);
}

TEST(ExperimentQueue, IdleCommandsNothing) {
  ExperimentQueue q;
  const ExperimentQueue::Step s = q.step(1.0);
  EXPECT_FALSE(s.active);
  EXPECT_FALSE(s.ended);
  EXPECT_FALSE(q.running());
  EXPECT_EQ(q.queued(), 0u);
}

// Starts at the first time it is asked about, runs whole periods (duration rounded up), and
// reports its end once.
TEST(ExperimentQueue, RunsWholePeriodsFromTheFirstStep) {
  ExperimentQueue q;
  const ExperimentSpec e = sine(100.0, 10.0, 0.25, 5.0);  // 2.5 periods -> 3 = 0.3 s
  q.add(e);
  EXPECT_TRUE(q.running());
  EXPECT_EQ(q.queued(), 0u);
  ExperimentQueue::Step s = q.step(1.0);
  ASSERT_TRUE(s.active);
  EXPECT_EQ(s.voltage_V, 5.0);  // phase 0
  s = q.step(1.025);            // a quarter period
  EXPECT_NEAR(s.voltage_V, 105.0, 1e-9);
  s = q.step(1.2999);
  EXPECT_TRUE(s.active);
  EXPECT_NEAR(s.voltage_V, voltage_at(e, 0.2999), 1e-9);
  s = q.step(1.3);
  EXPECT_FALSE(s.active);
  EXPECT_TRUE(s.ended);
  EXPECT_FALSE(q.running());
  s = q.step(1.4);
  EXPECT_FALSE(s.ended);  // once
}

TEST(ExperimentQueue, EndsAfterWholePeriodsForAnyDurationAndFrequency) {
  for (double f : {0.7, 1.0, 10.0, 33.3, 2900.0}) {
    for (double d : {1e-4, 0.05, 0.3, 1.0, 2.0, 7.77}) {
      const ExperimentSpec e = sine(1.0, f, d);
      const double periods = (experiment_end_s(3.0, e) - 3.0) * f;
      EXPECT_NEAR(periods, std::round(periods), 1e-6) << f << " Hz, " << d << " s";
      EXPECT_GE(periods / f, d - 1e-9) << f << " Hz, " << d << " s";
      EXPECT_LT(periods / f, d + 1.0 / f) << f << " Hz, " << d << " s";
    }
  }
  // A duration of exactly N periods is N periods, not N + 1 (2 s * 10 Hz is 20.000000000000004).
  EXPECT_NEAR(experiment_end_s(0.0, sine(1.0, 10.0, 2.0)), 2.0, 1e-12);
  EXPECT_NEAR(experiment_end_s(0.0, sine(1.0, 10.0, 0.3)), 0.3, 1e-12);
}

// A series is one continuous input: each experiment starts where the previous ended, at phase 0,
// however coarsely it is stepped.
TEST(ExperimentQueue, RunsASeriesBackToBack) {
  ExperimentQueue q;
  const std::vector<ExperimentSpec> specs = {sine(10.0, 50.0, 0.04), sine(3.0, 30.0, 0.01, 5.0),
                                             sine(2.0, 20.0, 0.1, -1.0)};
  for (const ExperimentSpec& e : specs) q.add(e);
  EXPECT_EQ(q.queued(), 2u);
  const double t0 = 0.5;
  const double end0 = experiment_end_s(t0, specs[0]);    // 0.54
  const double end1 = experiment_end_s(end0, specs[1]);  // + 1/30
  const double end2 = experiment_end_s(end1, specs[2]);  // + 0.1
  ASSERT_TRUE(q.step(t0).active);
  ExperimentQueue::Step s = q.step(end0 - 1e-6);
  EXPECT_NEAR(s.voltage_V, voltage_at(specs[0], end0 - 1e-6 - t0), 1e-9);
  s = q.step(end0);
  EXPECT_NEAR(s.voltage_V, 5.0, 1e-9);  // the second, at its phase 0
  EXPECT_EQ(q.queued(), 1u);
  // Skipping over the whole second experiment lands in the third at the right phase.
  s = q.step(end1 + 0.0125);
  ASSERT_TRUE(s.active);
  EXPECT_NEAR(s.voltage_V, voltage_at(specs[2], 0.0125), 1e-9);
  EXPECT_NEAR(s.voltage_V, -1.0 + 2.0, 1e-9);  // a quarter period of 20 Hz
  EXPECT_EQ(q.queued(), 0u);
  s = q.step(end2);
  EXPECT_TRUE(s.ended);
  EXPECT_FALSE(q.running());
}

TEST(ExperimentQueue, ASeriesSteppedPastItsEndEndsOnce) {
  ExperimentQueue q;
  for (int i = 0; i < 3; ++i) q.add(sine(1.0, 100.0, 0.01));
  ASSERT_TRUE(q.step(0.0).active);
  const ExperimentQueue::Step s = q.step(10.0);
  EXPECT_FALSE(s.active);
  EXPECT_TRUE(s.ended);
  EXPECT_EQ(q.queued(), 0u);
  EXPECT_FALSE(q.step(10.1).ended);
}

TEST(ExperimentQueue, StopEndsTheRunningOneAndDropsTheWaitingOnes) {
  ExperimentQueue q;
  for (int i = 0; i < 3; ++i) q.add(sine(10.0, 10.0, 1.0));
  ASSERT_TRUE(q.step(2.0).active);
  q.stop(2.05);  // mid-period: a stop is a stop
  EXPECT_EQ(q.queued(), 0u);
  EXPECT_TRUE(q.step(2.0499).active);
  ExperimentQueue::Step s = q.step(2.05);
  EXPECT_FALSE(s.active);
  EXPECT_TRUE(s.ended);
  EXPECT_FALSE(q.running());
  // A stop later than the natural end does not extend it.
  q.add(sine(10.0, 10.0, 0.1));
  ASSERT_TRUE(q.step(3.0).active);
  q.stop(5.0);
  EXPECT_TRUE(q.step(3.0999).active);
  EXPECT_TRUE(q.step(3.1).ended);
  // Stopped before it commanded anything: it never runs and never "ends".
  q.add(sine(10.0, 10.0, 0.1));
  q.add(sine(10.0, 10.0, 0.1));
  q.stop(4.0);
  EXPECT_FALSE(q.running());
  EXPECT_EQ(q.queued(), 0u);
  s = q.step(4.0);
  EXPECT_FALSE(s.active);
  EXPECT_FALSE(s.ended);
  q.stop(4.5);  // nothing to stop
  EXPECT_FALSE(q.step(4.6).active);
}

TEST(ExperimentQueue, AFullQueueIsRefusedAndTheRestStillRunsInOrder) {
  ExperimentQueue q;
  const std::size_t n = ExperimentQueue::kCapacity + 1;  // one running, kCapacity waiting
  for (std::size_t i = 0; i < n; ++i) q.add(sine(1.0, 1000.0, 1e-3, static_cast<double>(i)));
  EXPECT_EQ(q.queued(), ExperimentQueue::kCapacity);
  try {
    q.add(sine(1.0, 1000.0, 1e-3));
    FAIL() << "a full queue must be refused";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "experiment");
  }
  EXPECT_EQ(q.queued(), ExperimentQueue::kCapacity);
  // Each one at its phase 0 shows its offset: they run in the order given (the ring wraps).
  double t = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const ExperimentQueue::Step s = q.step(t);
    ASSERT_TRUE(s.active) << i;
    ASSERT_NEAR(s.voltage_V, static_cast<double>(i), 1e-9) << i;
    t = experiment_end_s(t, sine(1.0, 1000.0, 1e-3));
  }
  EXPECT_TRUE(q.step(t).ended);
  // Room again: the ring is reused.
  for (std::size_t i = 0; i < n; ++i) q.add(sine(1.0, 1000.0, 1e-3, 1000.0 + static_cast<double>(i)));
  EXPECT_NEAR(q.step(t + 1.0).voltage_V, 1000.0, 1e-9);
  EXPECT_NEAR(q.step(t + 1.0 + 5e-3).voltage_V, 1005.0, 1e-9);
}

TEST(ExperimentQueue, RefusesAnInvalidSpecNamingTheField) {
  ExperimentQueue q;
  ExperimentSpec bad = sine(1.0, 10.0, 1.0);
  bad.frequency_hz = 0.0;
  try {
    q.add(bad);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "experiment.frequency_hz");
  }
  EXPECT_FALSE(q.running());
  EXPECT_THROW(make_experiment_spec("chirp", 1.0, 0.0, 10.0, 1.0), ParameterError);
  EXPECT_TRUE(make_experiment_spec("settle", 1.0, 0.0, 10.0, 1.0).settle);
  EXPECT_FALSE(make_experiment_spec("sine", 1.0, 0.0, 10.0, 1.0).settle);
  EXPECT_THROW(make_experiment_spec("sine", -1.0, 0.0, 10.0, 1.0), ParameterError);
}

TEST(ExperimentQueue, StepAllocatesNothing) {
  ExperimentQueue q;
  for (int i = 0; i < 100; ++i) q.add(sine(1.0, 50.0 + i, 0.02));
  testing::AllocationCounter counter;
  double sum = 0.0;
  for (int k = 0; k < 100000; ++k) sum += q.step(k * 1e-4).voltage_V;
  q.stop(20.0);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

// The schedule's tick rounding is the compensator's comparison of loop time k * dt with the end.
TEST(ExperimentSchedule, FirstTickAtOrAfterMatchesTheLoopTimeComparison) {
  for (double dt : {1e-4, 1.0 / 3e4, 2.5e-4}) {
    for (int i = 1; i < 20000; ++i) {
      const double t = 0.000137 * i + (i % 7) * 1e-13;
      const std::int64_t k = first_tick_at_or_after(t, dt);
      ASSERT_GE(static_cast<double>(k) * dt, t);
      ASSERT_LT(static_cast<double>(k - 1) * dt, t);
    }
  }
  EXPECT_EQ(first_tick_at_or_after(0.3, 1e-4), 3000);  // exactly on a tick
}

TEST(ExperimentSchedule, TicksOfASeriesRunBackToBack) {
  const std::vector<ExperimentSpec> specs = {sine(10.0, 50.0, 0.04), sine(3.0, 30.0, 0.01),
                                             sine(2.0, 2900.0, 3.0 / 2900.0)};
  const auto ticks = experiment_schedule(1234, specs, 1e-4);
  ASSERT_EQ(ticks.size(), 3u);
  EXPECT_EQ(ticks[0].begin, 1234);
  EXPECT_EQ(ticks[0].end - ticks[0].begin, 400);  // 2 periods of 50 Hz
  EXPECT_EQ(ticks[1].begin, ticks[0].end);
  EXPECT_EQ(ticks[1].end - ticks[1].begin, 334);  // 1 period of 30 Hz: 333.3 ticks
  EXPECT_EQ(ticks[2].begin, ticks[1].end);
  // The third ends on the tick at or after the series' exact end time.
  EXPECT_EQ(ticks[2].end, first_tick_at_or_after(0.1234 + 0.04 + 1.0 / 30.0 + 3.0 / 2900.0, 1e-4));
}

}  // namespace
}  // namespace hystloop
