#include "loop/compensator.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
