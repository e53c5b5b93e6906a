// Identification experiments in the compensator's plan: they start at the first tick not yet
// planned, run whole periods back to back on the schedule experiment_schedule() reproduces, are
// followed by hold ticks (last voltage, no reference) until the sample of the first tick after
// them is observed, and tracking then resumes from where the stage was measured.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "loop/compensator_rig.hpp"
#include "core/errors.hpp"
#include "loop/compensator.hpp"
#include "loop/experiment.hpp"
#include "sim/loop_simulation.hpp"

namespace hystloop {
namespace {

using testing::compensator_config;
using testing::CompensatorLoop;
using testing::kDt;

constexpr auto kExperimentMode = static_cast<std::int8_t>(FeedforwardMode::kExperiment);

ExperimentSpec sine(double amplitude_V, double frequency_hz, double duration_s, double offset_V = 0.0) {
  return make_experiment_spec("sine", amplitude_V, offset_V, frequency_hz, duration_s);
}

// 1 um cosine around 0: within the default MEM stage's reach.
TrajectorySpec cosine_reference() {
  TrajectorySpec s = mem_paper_reference(0.0, 0.2);
  s.amplitude_m = -1.0e-6;
  return s;
}

struct ExperimentRun {
  std::int64_t first = 0;    // first experiment tick: the first not yet planned at the start
  std::int64_t end = 0;      // first tick after it
  std::int64_t resumed = 0;  // first tick planned after the end's sample was observed
};

// Tracks for 0.3 s, runs `e`, tracks again for `after_ticks`.
ExperimentRun run_experiment(CompensatorLoop& loop, const ExperimentSpec& e, std::int64_t after_ticks) {
  loop.comp.set_trajectory(cosine_reference(), std::numeric_limits<double>::quiet_NaN());
  loop.run(3000);
  ExperimentRun r;
  loop.comp.start_experiment(e);
  r.first = loop.comp.next_tick();
  r.end = experiment_schedule(r.first, std::vector<ExperimentSpec>{e}, kDt).front().end;
  r.resumed = -1;
  loop.run(r.end - loop.k + after_ticks, [&](std::int64_t k) {
    if (k == r.end) r.resumed = loop.comp.next_tick();
  });
  return r;
}

TEST(CompensatorExperiment, StartsAtTheNextPlannedTickAndRunsWholePeriods) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  const ExperimentSpec e = sine(100.0, 50.0, 0.05, 10.0);  // 2.5 periods -> 3 = 600 ticks
  const ExperimentRun r = run_experiment(loop, e, 1000);
  EXPECT_EQ(r.first, 3000 + 50);  // after sample 2999 the plan reached 2999 + horizon
  EXPECT_EQ(r.end - r.first, 600);
  EXPECT_NE(loop.plan.at(r.first - 1).mode, kExperimentMode);
  for (std::int64_t k = r.first; k < r.end; ++k) {
    const CommandTick& t = loop.plan.at(k);
    ASSERT_EQ(t.mode, kExperimentMode) << k;
    ASSERT_TRUE(std::isnan(t.y_ref_m)) << k;
    ASSERT_NEAR(t.u_ff_V, experiment_voltage(e, static_cast<double>(k - r.first) * kDt), 1e-9) << k;
  }
  EXPECT_EQ(loop.plan.at(r.first).u_ff_V, 10.0);  // phase 0
  EXPECT_FALSE(loop.comp.experiment_running());
}

// After the experiment the plan cannot know where the stage ended up until the sample of the
// experiment's end arrives: it holds the last voltage without a reference (the bridge's servo
// rests), then anchors the inverse at the measured (u, y) and approaches the reference from y.
TEST(CompensatorExperiment, HoldsUntilItsEndIsMeasuredThenResumesFromTheMeasuredPosition) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  const ExperimentSpec e = sine(100.0, 50.0, 0.05, 10.0);
  const ExperimentRun r = run_experiment(loop, e, 8000);
  ASSERT_GT(r.resumed, r.end);
  EXPECT_EQ(r.resumed, r.end + 50);  // the plan had reached end + horizon - 1 when sample `end` came
  const double last_experiment_u = loop.plan.at(r.end - 1).u_ff_V;
  constexpr auto kMem = static_cast<std::int8_t>(FeedforwardMode::kMem);
  for (std::int64_t k = r.end; k < r.resumed; ++k) {
    const CommandTick& t = loop.plan.at(k);
    ASSERT_EQ(t.mode, kMem) << k;  // the tracking mode: the bridge and logs see the experiment ended
    ASSERT_TRUE(std::isnan(t.y_ref_m)) << k;
    ASSERT_EQ(t.u_ff_V, last_experiment_u) << k;
  }
  const CommandTick& first = loop.plan.at(r.resumed);
  EXPECT_EQ(first.mode, kMem);
  EXPECT_EQ(first.y_ref_m, loop.y_measured[static_cast<std::size_t>(r.end)]);  // from where the stage is
  EXPECT_NEAR(first.u_ff_V, last_experiment_u, 1e-9);                          // and no voltage jump
  // From there on the voltage moves only as much as the reference's moves require: on a MEM
  // branch |du| <= |dy| / c1, the slope's minimum.
  const double c1 = loop.comp.mem_params().c1;
  for (std::int64_t k = r.resumed + 1; k < loop.k; ++k) {
    const CommandTick& a = loop.plan.at(k - 1);
    const CommandTick& b = loop.plan.at(k);
    ASSERT_LE(std::abs(b.u_ff_V - a.u_ff_V), std::abs(b.y_ref_m - a.y_ref_m) / c1 * (1 + 1e-9) + 1e-12) << k;
    ASSERT_LT(std::abs(b.y_ref_m - a.y_ref_m), 2e-9) << k;  // a smooth approach: no step in the reference
  }
}

// The stage is exactly the compensator's MEM model: once the approach is over, it tracks the
// reference to rounding, whichever way the reference leaves the anchor. The experiments below end
// rising (a sine after whole periods); the reference then leaves the end point downward (a
// reversal: the stage starts a new branch there, as the anchored inverse does) or upward (the
// stage goes on along the branch that began at the sine's last trough).
TEST(CompensatorExperiment, TrackingIsExactAfterTheApproachOnAnExactModel) {
  for (double offset_V : {10.0, -220.0}) {
    CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
    const ExperimentRun r = run_experiment(loop, sine(100.0, 50.0, 0.05, offset_V), 12000);
    const double y_end = loop.y_measured[static_cast<std::size_t>(r.end)];
    const double y_later = loop.plan.at(r.resumed + 100).y_ref_m;
    double worst = 0.0;
    for (std::int64_t k = r.resumed + 6000; k < loop.k; ++k) {
      worst = std::max(worst, std::abs(loop.y_measured[static_cast<std::size_t>(k)] - loop.plan.at(k).y_ref_m));
    }
    EXPECT_LT(worst, 1e-12) << "offset " << offset_V << " V: the reference left y = " << y_end * 1e9 << " nm "
                            << (y_later > y_end ? "upward" : "downward");
  }
}

TEST(CompensatorExperiment, StopEndsItAtTheFirstTickNotYetPlannedAndDropsTheQueue) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.comp.set_trajectory(cosine_reference(), std::numeric_limits<double>::quiet_NaN());
  loop.run(1000);
  loop.comp.start_experiment(sine(100.0, 10.0, 1.0));
  loop.comp.start_experiment(sine(100.0, 10.0, 1.0));
  loop.run(2000);
  std::int64_t stopped_at = -1;
  std::int64_t resumed = -1;
  loop.run(3000, [&](std::int64_t k) {
    if (k == 3000) {
      loop.comp.stop_experiment();
      stopped_at = loop.comp.next_tick();
      EXPECT_EQ(loop.comp.experiments_queued(), 0u);
    }
    if (stopped_at >= 0 && k == stopped_at) resumed = loop.comp.next_tick();
  });
  ASSERT_GT(stopped_at, 3000);
  EXPECT_EQ(loop.plan.at(stopped_at - 1).mode, kExperimentMode);  // sent: stays
  EXPECT_NE(loop.plan.at(stopped_at).mode, kExperimentMode);
  EXPECT_TRUE(std::isnan(loop.plan.at(stopped_at).y_ref_m));
  EXPECT_EQ(loop.plan.at(stopped_at).u_ff_V, loop.plan.at(stopped_at - 1).u_ff_V);
  ASSERT_GT(resumed, stopped_at);
  EXPECT_EQ(loop.plan.at(resumed).y_ref_m, loop.y_measured[static_cast<std::size_t>(stopped_at)]);
  EXPECT_FALSE(loop.comp.experiment_running());
  for (std::int64_t k = resumed; k < loop.k; ++k) ASSERT_NE(loop.plan.at(k).mode, kExperimentMode) << k;
  // Stopped before its first tick was planned: it never runs.
  loop.comp.start_experiment(sine(100.0, 10.0, 1.0));
  loop.comp.stop_experiment();
  EXPECT_FALSE(loop.comp.experiment_running());
  loop.run(100);
  EXPECT_NE(loop.plan.ticks().back().mode, kExperimentMode);
}

// Experiments given while one runs wait and run back to back, each from where the previous one
// ended (whole periods, phase 0), on the ticks experiment_schedule() computes for a log.
TEST(CompensatorExperiment, AQueuedSeriesRunsOnTheSchedule) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kOff, 30));
  std::vector<ExperimentSpec> specs = {sine(10.0, 50.0, 0.04), sine(3.0, 30.0, 0.01, 5.0),
                                       sine(2.0, 2900.0, 3.0 / 2900.0)};  // 2 periods; 1, rounded up; off-tick
  specs[1].settle = true;
  loop.run(10);
  for (const ExperimentSpec& s : specs) loop.comp.start_experiment(s);
  EXPECT_TRUE(loop.comp.experiment_running());
  EXPECT_EQ(loop.comp.experiments_queued(), 2u);
  const std::int64_t first = loop.comp.next_tick();
  loop.run(2000);
  const auto ticks = experiment_schedule(first, specs, kDt);
  ASSERT_EQ(ticks.size(), 3u);
  EXPECT_EQ(ticks[0].end - ticks[0].begin, 400);
  EXPECT_EQ(ticks[1].end - ticks[1].begin, 334);
  double start_s = static_cast<double>(first) * kDt;
  for (std::size_t e = 0; e < specs.size(); ++e) {
    for (std::int64_t k = ticks[e].begin; k < ticks[e].end; ++k) {
      const CommandTick& t = loop.plan.at(k);
      ASSERT_EQ(t.mode, kExperimentMode) << k;
      ASSERT_NEAR(t.u_ff_V, experiment_voltage(specs[e], static_cast<double>(k) * kDt - start_s), 1e-9) << k;
    }
    start_s = experiment_end_s(start_s, specs[e]);
  }
  EXPECT_NE(loop.plan.at(first - 1).mode, kExperimentMode);
  EXPECT_EQ(loop.plan.at(ticks.back().end).mode, static_cast<std::int8_t>(FeedforwardMode::kOff));
  EXPECT_FALSE(loop.comp.experiment_running());
  EXPECT_EQ(loop.comp.experiments_queued(), 0u);
  std::vector<ExperimentSpec> too_many(ExperimentQueue::kCapacity + 2, specs[0]);
  try {
    for (const ExperimentSpec& s : too_many) loop.comp.start_experiment(s);
    FAIL() << "a full queue must be refused";
  } catch (const ParameterError& err) {
    EXPECT_EQ(err.field(), "experiment");
  }
}

// A trajectory given a start time while an experiment runs starts then, not when the experiment
// happens to end: set_trajectory() said it would.
TEST(CompensatorExperiment, ATimedTrajectoryGivenDuringAnExperimentStartsOnTime) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  loop.comp.start_experiment(sine(100.0, 10.0, 0.2));  // ticks 150..2149
  TrajectorySpec ref = cosine_reference();
  ref.blend_s = 0.1;
  ASSERT_TRUE(loop.comp.set_trajectory(ref, 1.0));  // approach from t = 0.9 s, shape from 1.0 s
  loop.run(12000);
  EXPECT_NEAR(loop.plan.at(10000).y_ref_m, -1.0e-6, 1e-15);  // the shape's start, at 1.0 s
  EXPECT_NEAR(loop.plan.at(12000).y_ref_m, -1.0e-6 * std::cos(2.0 * 3.141592653589793 * 0.2), 1e-15);
  // It still approaches from where the stage was measured after the experiment (ended at 2150,
  // measured with the plan at 2199).
  EXPECT_TRUE(std::isnan(loop.plan.at(2199).y_ref_m));
  EXPECT_EQ(loop.plan.at(2200).y_ref_m, loop.y_measured[2150]);
}

// On the Ramberg-Osgood stage (the MEM shape is exact) through the whole loop: after an
// identification experiment the inverse is anchored where the stage really is (not on a virgin
// skeleton), so tracking is exact.
TEST(CompensatorExperiment, TrackingThroughTheLoopAfterAnExperimentStartsFromWhereTheStageIs) {
  LoopSimulationConfig c;
  c.stage.plant = PlantKind::kRambergOsgood;
  c.stage.noise_rms_m = 0.0;
  c.compensator.mode = FeedforwardMode::kMem;
  LoopSimulation sim(c);
  ExperimentSpec e;
  e.amplitude_V = 200.0;
  e.duration_s = 1.0;
  sim.compensator().start_experiment(e);
  TrajectorySpec ref = mem_paper_reference(0.0, 0.5);
  ref.amplitude_m = -1.2e-6;  // inside the plant's reach at +-250 V
  sim.compensator().set_trajectory(ref, std::numeric_limits<double>::quiet_NaN());
  sim.run(5.0);
  EXPECT_FALSE(sim.compensator().experiment_running());
  const TrackingStats s = sim.tracking(2.0, 5.0);
  ASSERT_GT(s.n, 20000u);
  EXPECT_LT(s.rms_true_m, 1e-11);  // rounding; a virgin-skeleton start would be off by nanometres
  // The bridge arms at the first plan (as its auto_arm does), so no tick waits on a command.
  EXPECT_EQ(sim.bridge().counters().late, 0u);
}

}  // namespace
}  // namespace hystloop
