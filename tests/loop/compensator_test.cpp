#include "loop/compensator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/errors.hpp"
#include "loop/loop_simulation.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

CompensatorConfig mem_config() {
  CompensatorConfig c;
  c.mode = FeedforwardMode::kMem;
  return c;
}

TEST(Compensator, AnswersSampleKWithTheCommandForKPlusLead) {
  Compensator comp(mem_config());
  const auto out = comp.update({10, 0.0, 0.0});
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->seq, 12);
  EXPECT_EQ(out->sample_seq, 10);
  EXPECT_FALSE(comp.update({10, 0.0, 0.0}).has_value());  // not newer: ignored
  EXPECT_EQ(comp.counters().out_of_order, 1u);
  comp.update({15, 0.0, 0.0});
  EXPECT_EQ(comp.counters().gaps, 4u);
}

// The compensator is a function of its inputs: two instances fed the same messages agree to the bit.
TEST(Compensator, IsDeterministic) {
  Compensator a(mem_config()), b(mem_config());
  a.set_trajectory(mem_paper_reference(0.1, 0.1));
  b.set_trajectory(mem_paper_reference(0.1, 0.1));
  for (std::int64_t k = 0; k < 30000; ++k) {
    const double y = 1e-7 * std::sin(0.001 * static_cast<double>(k));
    if (k == 12000) {
      MemParams p;
      p.c1 *= 1.1;
      a.offer_mem_params(p, 2);
      b.offer_mem_params(p, 2);
    }
    const auto oa = a.update({k, 0.0, y});
    const auto ob = b.update({k, 0.0, y});
    ASSERT_EQ(oa->u_V, ob->u_V) << k;
  }
}

TEST(Compensator, SwapsParametersOnlyAtAReversalAndWithoutABump) {
  Compensator comp(mem_config());
  comp.set_trajectory(mem_paper_reference(0.0));  // reversals at t = 0.5, 1.0, ...
  std::int64_t k = 0;
  for (; k < 2000; ++k) comp.update({k, 0.0, 0.0});  // t = 0.2 s: rising
  MemParams p;
  p.c1 *= 1.2;
  comp.offer_mem_params(p, 5);
  double prev_u = 0.0;
  double max_step = 0.0;
  std::int64_t swapped_at = -1;
  for (; k < 12000; ++k) {
    const auto out = comp.update({k, 0.0, 0.0});
    if (k > 2000) max_step = std::max(max_step, std::abs(out->u_V - prev_u));
    if (swapped_at < 0 && out->params_version == 5) {
      swapped_at = out->seq;
      EXPECT_TRUE(out->reversal);
    }
    prev_u = out->u_V;
  }
  // The reference peaks at t = 0.5 s (tick 5000); tick 5001 is the first that moves back.
  EXPECT_EQ(swapped_at, 5001);
  EXPECT_EQ(comp.counters().params_swapped, 1u);
  EXPECT_LT(max_step, 0.5);  // a smooth 1 Hz sweep of ~+-250 V moves < 0.2 V per tick: no jump
}

TEST(Compensator, RefusesInvalidParametersAndKeepsTheOldOnes) {
  Compensator comp(mem_config());
  MemParams bad;
  bad.c3 = -1.0;
  EXPECT_THROW(comp.offer_mem_params(bad, 2), ParameterError);
  EXPECT_EQ(comp.counters().params_rejected, 1u);
  EXPECT_EQ(comp.mem_params().c3, MemParams{}.c3);
}

TEST(Compensator, UpdateAllocatesNothing) {
  CompensatorConfig c = mem_config();
  c.feedback.ki = 100.0;
  Compensator comp(c);
  comp.set_trajectory(mem_paper_reference(0.0));
  testing::AllocationCounter counter;
  for (std::int64_t k = 0; k < 20000; ++k) comp.update({k, 0.0, 1e-9});
  EXPECT_EQ(counter.allocations(), 0u);
}

// On a Ramberg-Osgood plant the MEM inverse is exact: after an identification experiment the
// inverse is anchored where the stage really is (not on a virgin skeleton), so tracking is exact.
TEST(Compensator, TrackingAfterAnExperimentStartsFromWhereTheStageIs) {
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
  sim.compensator().set_trajectory(ref);
  sim.run(5.0);
  EXPECT_FALSE(sim.compensator().experiment_running());
  const TrackingStats s = sim.tracking(2.0, 5.0);
  ASSERT_GT(s.n, 20000u);
  EXPECT_LT(s.rms_true_m, 1e-11);  // rounding; a virgin-skeleton start would be off by nanometres
}

// Experiments given while one runs wait and run back to back, each from where the previous one
// ended (whole periods, phase 0), on the schedule experiment_schedule() computes for a log.
TEST(Compensator, QueuedExperimentsRunBackToBackOnTheSchedule) {
  CompensatorConfig c;
  c.mode = FeedforwardMode::kOff;
  Compensator comp(c);
  std::vector<ExperimentSpec> specs(3);
  specs[0].amplitude_V = 10.0, specs[0].frequency_hz = 50.0, specs[0].duration_s = 0.04;            // 2 periods
  specs[1].amplitude_V = 3.0, specs[1].offset_V = 5.0, specs[1].frequency_hz = 30.0;                // 1 period,
  specs[1].duration_s = 0.01, specs[1].settle = true;                                               // rounded up
  specs[2].amplitude_V = 2.0, specs[2].frequency_hz = 2900.0, specs[2].duration_s = 3.0 / 2900.0;  // not on a tick
  std::int64_t seq = 0;
  for (; seq < 10; ++seq) ASSERT_TRUE(comp.update({seq, 0.0, 0.0}));
  for (const auto& s : specs) comp.start_experiment(s);
  EXPECT_TRUE(comp.experiment_running());
  EXPECT_EQ(comp.experiments_queued(), 2u);
  std::vector<CompensatorOutput> out;
  for (; seq < 2000; ++seq) out.push_back(*comp.update({seq, 0.0, 0.0}));
  ASSERT_EQ(out.front().mode, FeedforwardMode::kExperiment);
  const std::int64_t first = out.front().seq;
  EXPECT_EQ(first, 10 + c.lead_ticks);  // the next command
  const auto ticks = experiment_schedule(first, specs, c.dt_s);
  ASSERT_EQ(ticks.size(), 3u);
  EXPECT_EQ(ticks[0].end - ticks[0].begin, 400);   // 2 periods of 50 Hz
  EXPECT_EQ(ticks[1].end - ticks[1].begin, 334);   // 1 period of 30 Hz: 333.3 ticks
  double start_s = static_cast<double>(first) * c.dt_s;
  std::size_t i = 0;
  for (std::size_t e = 0; e < specs.size(); ++e) {
    for (std::int64_t k = ticks[e].begin; k < ticks[e].end; ++k, ++i) {
      ASSERT_EQ(out[i].seq, k);
      ASSERT_EQ(out[i].mode, FeedforwardMode::kExperiment) << k;
      const double t = static_cast<double>(k) * c.dt_s - start_s;
      EXPECT_NEAR(out[i].u_V, specs[e].offset_V + specs[e].amplitude_V * std::sin(2.0 * std::numbers::pi *
                                                                                  specs[e].frequency_hz * t), 1e-9);
    }
    start_s = experiment_end_s(start_s, specs[e]);
  }
  EXPECT_EQ(out[i].seq, ticks.back().end);
  EXPECT_EQ(out[i].mode, FeedforwardMode::kOff);  // back to the mode, queue empty
  EXPECT_FALSE(comp.experiment_running());
  EXPECT_EQ(comp.experiments_queued(), 0u);
}

TEST(Compensator, StopExperimentDropsTheQueueAndAFullQueueIsRefused) {
  Compensator comp(mem_config());
  std::int64_t seq = 0;
  for (; seq < 5; ++seq) comp.update({seq, 0.0, 0.0});
  ExperimentSpec e;
  for (std::size_t i = 0; i <= Compensator::kExperimentQueue; ++i) comp.start_experiment(e);
  EXPECT_EQ(comp.experiments_queued(), Compensator::kExperimentQueue);
  try {
    comp.start_experiment(e);
    FAIL() << "a full queue must be refused";
  } catch (const ParameterError& err) {
    EXPECT_EQ(err.field(), "experiment");
  }
  for (; seq < 100; ++seq) EXPECT_EQ(comp.update({seq, 0.0, 0.0})->mode, FeedforwardMode::kExperiment);
  comp.stop_experiment();
  EXPECT_EQ(comp.experiments_queued(), 0u);
  EXPECT_NE(comp.update({seq++, 0.0, 0.0})->mode, FeedforwardMode::kExperiment);
  EXPECT_FALSE(comp.experiment_running());
  // Stopped before its first command: it never runs.
  comp.start_experiment(e);
  comp.stop_experiment();
  EXPECT_FALSE(comp.experiment_running());
  EXPECT_NE(comp.update({seq++, 0.0, 0.0})->mode, FeedforwardMode::kExperiment);
}

// The schedule's tick rounding is the compensator's test t_cmd < end: k * dt >= t exactly.
TEST(Compensator, FirstTickAtOrAfterMatchesTheLoopTimeComparison) {
  for (double dt : {1e-4, 1.0 / 3e4, 2.5e-4}) {
    for (int i = 1; i < 20000; ++i) {
      const double t = 0.000137 * i + (i % 7) * 1e-13;
      const std::int64_t k = first_tick_at_or_after(t, dt);
      EXPECT_GE(static_cast<double>(k) * dt, t);
      EXPECT_LT(static_cast<double>(k - 1) * dt, t);
    }
  }
}

TEST(Compensator, ConfigValidationNamesTheField) {
  CompensatorConfig c = mem_config();
  c.lead_ticks = 0;
  try {
    Compensator comp(c);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "compensator.lead_ticks");
  }
  EXPECT_THROW(parse_feedforward_mode("memm"), ParameterError);
  EXPECT_EQ(parse_feedforward_mode("katalenic"), FeedforwardMode::kKatalenic);
}

}  // namespace
}  // namespace hystloop
