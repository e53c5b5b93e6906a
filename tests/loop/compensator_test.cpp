// The compensator runs ahead of the bridge (docs/TIMING.md): after sample k it has planned
// every tick through k + horizon, each exactly once, and anything new takes effect at the first
// tick not yet planned. Experiments have their own file: compensator_experiment_test.cpp.
#include "loop/compensator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "compensator_rig.hpp"
#include "core/errors.hpp"
#include "loop/command_buffer.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testing::compensator_config;
using testing::kDt;
using testing::PlanRecorder;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Compensator, PlansNothingBeforeTheFirstSample) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  std::vector<CommandTick> out(100);
  EXPECT_EQ(comp.plan(out), 0u);
  EXPECT_EQ(comp.next_tick(), -1);
  EXPECT_EQ(comp.last_seq(), -1);
}

TEST(Compensator, PlansExactlyThroughTheLastSamplePlusTheHorizonAndNeverReplans) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  PlanRecorder rec;
  comp.observe({100, 0.0, 0.0});
  EXPECT_EQ(rec.drain(comp), 50u);  // 101..150
  EXPECT_EQ(rec.ticks().front().seq, 101);
  EXPECT_EQ(rec.ticks().back().seq, 150);
  EXPECT_EQ(rec.drain(comp), 0u);  // complete: nothing twice
  comp.observe({101, 0.0, 0.0});
  EXPECT_EQ(rec.drain(comp), 1u);
  EXPECT_EQ(rec.ticks().back().seq, 151);
  for (std::int64_t s = 102; s <= 110; ++s) comp.observe({s, 0.0, 0.0});
  // A span smaller than what is due gets what fits; the rest follows.
  std::vector<CommandTick> three(3);
  ASSERT_EQ(comp.plan(three), 3u);
  EXPECT_EQ(three[0].seq, 152);
  EXPECT_EQ(three[2].seq, 154);
  EXPECT_EQ(comp.next_tick(), 155);
  EXPECT_EQ(rec.drain(comp), 6u);  // 155..160
  EXPECT_EQ(rec.ticks().back().seq, 160);
  EXPECT_EQ(comp.counters().planned, 60u);
  EXPECT_EQ(comp.counters().ticks_behind, 0u);
  // Old and repeated samples are ignored and plan nothing.
  comp.observe({110, 0.0, 0.0});
  comp.observe({50, 0.0, 0.0});
  EXPECT_EQ(comp.counters().out_of_order, 2u);
  EXPECT_EQ(rec.drain(comp), 0u);
  // A gap in the samples is counted; the plan reaches the new sample + horizon.
  comp.observe({115, 0.0, 0.0});
  EXPECT_EQ(comp.counters().gaps, 4u);
  EXPECT_EQ(rec.drain(comp), 5u);
  EXPECT_EQ(comp.next_tick(), 166);
}

TEST(Compensator, CatchesUpAfterAStall) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  PlanRecorder rec;
  comp.observe({0, 0.0, 0.0});
  EXPECT_EQ(rec.drain(comp), 50u);  // 1..50
  // The planner stalls (shorter than the horizon) while samples keep coming: one plan call
  // catches up to the last sample + horizon.
  for (std::int64_t s = 1; s < 40; ++s) comp.observe({s, 0.0, 0.0});
  EXPECT_EQ(rec.drain(comp), 39u);  // 51..89
  EXPECT_EQ(rec.ticks().back().seq, 89);
  // The samples stall (the plan is complete meanwhile); one within the plan extends it, no skip.
  for (int i = 0; i < 10; ++i) EXPECT_EQ(rec.drain(comp), 0u);
  comp.observe({80, 0.0, 0.0});
  EXPECT_EQ(rec.drain(comp), 41u);  // 90..130
  EXPECT_EQ(rec.ticks().back().seq, 130);
  EXPECT_EQ(comp.counters().ticks_behind, 0u);
  EXPECT_EQ(comp.counters().gaps, 40u);
  EXPECT_EQ(rec.ticks().size(), 130u);  // 1..130, each once
}

// A sample for a tick not yet planned means the bridge got there first: those ticks are lost
// (counted), and the plan goes on from the tick after the sample.
TEST(Compensator, BehindTheBridgeSkipsTicksAndCountsThem) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  PlanRecorder rec;
  comp.observe({0, 0.0, 0.0});
  rec.drain(comp);  // 1..50
  comp.observe({80, 0.0, 0.0});
  EXPECT_EQ(comp.counters().ticks_behind, 30u);  // 51..80
  EXPECT_EQ(comp.next_tick(), 81);
  EXPECT_EQ(rec.drain(comp), 50u);
  EXPECT_EQ(rec.find(80), nullptr);
  EXPECT_EQ(rec.at(81).seq, 81);
  EXPECT_EQ(rec.ticks().back().seq, 130);
  comp.observe({131, 0.0, 0.0});  // exactly the next tick: already applied (late) by the bridge
  EXPECT_EQ(comp.counters().ticks_behind, 31u);
  EXPECT_EQ(rec.drain(comp), 50u);
  EXPECT_EQ(rec.ticks().front().seq, 1);
  EXPECT_EQ(rec.ticks().back().seq, 181);
}

TEST(Compensator, ANewTrajectoryTakesEffectAtTheFirstTickNotYetPlanned) {
  Compensator comp(compensator_config(FeedforwardMode::kLinear, 50));
  PlanRecorder rec;
  comp.observe({0, 0.0, 0.0});
  rec.drain(comp);  // 1..50: hold at 0
  TrajectorySpec step;
  step.offset_m = 1e-6;  // a hold at 1 um, no approach
  EXPECT_TRUE(comp.set_trajectory(step, kNaN));
  comp.observe({1, 0.0, 0.0});
  rec.drain(comp);
  for (std::int64_t s = 1; s <= 50; ++s) ASSERT_EQ(rec.at(s).y_ref_m, 0.0) << s;  // sent: unchanged
  EXPECT_EQ(rec.at(51).y_ref_m, 1e-6);
  EXPECT_EQ(rec.at(51).mode, static_cast<std::int8_t>(FeedforwardMode::kLinear));
  EXPECT_GT(rec.at(51).u_ff_V, rec.at(50).u_ff_V);
  // With an approach: it starts from the reference planned last, at the first unplanned tick.
  TrajectorySpec back;
  back.blend_s = 0.01;  // 100 ticks back to 0
  EXPECT_TRUE(comp.set_trajectory(back, kNaN));
  for (std::int64_t s = 2; s <= 110; ++s) {  // sample by sample: the plan stays ahead of them
    comp.observe({s, 0.0, 0.0});
    rec.drain(comp);
  }
  EXPECT_EQ(comp.counters().ticks_behind, 0u);
  EXPECT_EQ(rec.at(52).y_ref_m, 1e-6);  // hold_m: the approach begins here
  EXPECT_LT(rec.at(53).y_ref_m, 1e-6);
  EXPECT_NEAR(rec.at(102).y_ref_m, 0.5e-6, 1e-15);
  EXPECT_NEAR(rec.at(152).y_ref_m, 0.0, 1e-21);
  for (std::int64_t s = 53; s <= 152; ++s) ASSERT_LT(rec.at(s).y_ref_m, rec.at(s - 1).y_ref_m + 1e-21) << s;
}

// A start time that has passed cannot be honoured: it starts as soon as possible, exactly as an
// untimed one, and the caller hears false.
TEST(Compensator, ATimedStartInThePastStartsNowAndReturnsFalse) {
  const TrajectorySpec ref = mem_paper_reference(0.0, 0.005);
  Compensator late(compensator_config(FeedforwardMode::kMem, 50));
  Compensator asap(compensator_config(FeedforwardMode::kMem, 50));
  PlanRecorder late_plan, asap_plan;
  for (std::int64_t s = 0; s < 100; ++s) {
    late.observe({s, 0.0, 0.0});
    asap.observe({s, 0.0, 0.0});
  }
  late_plan.drain(late);
  asap_plan.drain(asap);                          // through 149: the next planned tick is 150 (t = 0.015 s)
  EXPECT_FALSE(late.set_trajectory(ref, 0.016));  // its approach would start at 0.011 s: passed
  EXPECT_TRUE(asap.set_trajectory(ref, kNaN));
  for (std::int64_t s = 100; s < 2000; ++s) {
    late.observe({s, 0.0, 0.0});
    asap.observe({s, 0.0, 0.0});
    late_plan.drain(late);
    asap_plan.drain(asap);
  }
  ASSERT_EQ(late_plan.ticks().size(), asap_plan.ticks().size());
  for (std::size_t i = 0; i < late_plan.ticks().size(); ++i) {
    ASSERT_TRUE(testing::same_tick(late_plan.ticks()[i], asap_plan.ticks()[i])) << late_plan.ticks()[i].seq;
  }
  // The approach starts at the next planned tick (there its quintic is s^3 of a rounding error).
  EXPECT_NEAR(asap_plan.at(150).y_ref_m, 0.0, 1e-30);
  EXPECT_LT(asap_plan.at(151).y_ref_m, -1e-16);
  EXPECT_NEAR(asap_plan.at(200).y_ref_m, -1.6e-6, 1e-18);  // ... and reaches the shape after blend_s
}

TEST(Compensator, ATimedStartInTheFutureIsHonoured) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  PlanRecorder rec;
  for (std::int64_t s = 0; s < 100; ++s) comp.observe({s, 0.0, 0.0});
  rec.drain(comp);  // next planned tick: 150
  // The approach may begin before the tick after next: not passed yet.
  EXPECT_TRUE(comp.set_trajectory(mem_paper_reference(0.0, 0.005), 150.5 * kDt + 0.005));
  TrajectorySpec later = mem_paper_reference(0.0, 0.005);
  later.amplitude_m = -1.0e-6;
  EXPECT_TRUE(comp.set_trajectory(later, 0.03));  // replaces it: approach 250..299, shape from 300
  for (std::int64_t s = 100; s < 1000; ++s) {
    comp.observe({s, 0.0, 0.0});
    rec.drain(comp);
  }
  for (std::int64_t s = 150; s <= 250; ++s) ASSERT_NEAR(rec.at(s).y_ref_m, 0.0, 1e-30) << s;  // held
  EXPECT_LT(rec.at(251).y_ref_m, 0.0);
  EXPECT_NEAR(rec.at(300).y_ref_m, -1.0e-6, 1e-18);
  EXPECT_NEAR(rec.at(550).y_ref_m, -1.0e-6 * std::cos(2.0 * 3.141592653589793 * 0.025), 1e-15);
}

TEST(Compensator, AModeChangeTakesEffectAtTheFirstTickNotYetPlannedWithoutAJumpIntoMem) {
  Compensator comp(compensator_config(FeedforwardMode::kLinear, 50));
  PlanRecorder rec;
  comp.set_trajectory(mem_paper_reference(0.0, 0.05), 0.05);
  std::int64_t switched_at = -1;
  for (std::int64_t s = 0; s < 8000; ++s) {
    comp.observe({s, 0.0, 0.0});
    if (s == 3000) {
      comp.set_mode(FeedforwardMode::kMem);
      switched_at = comp.next_tick();
    }
    rec.drain(comp);
  }
  constexpr auto kLinear = static_cast<std::int8_t>(FeedforwardMode::kLinear);
  constexpr auto kMem = static_cast<std::int8_t>(FeedforwardMode::kMem);
  EXPECT_EQ(rec.at(switched_at - 1).mode, kLinear);
  EXPECT_EQ(rec.at(switched_at).mode, kMem);
  EXPECT_EQ(rec.ticks().back().mode, kMem);
  // MEM starts on a branch through the last planned (u, y_ref): the voltage continues.
  const double step = std::abs(rec.at(switched_at).u_ff_V - rec.at(switched_at - 1).u_ff_V);
  const double before = std::abs(rec.at(switched_at - 1).u_ff_V - rec.at(switched_at - 2).u_ff_V);
  EXPECT_LT(step, 3.0 * before + 1e-6);
  EXPECT_THROW(comp.set_mode(FeedforwardMode::kExperiment), ParameterError);
}

// New MEM parameters wait for a reversal of the planned reference, where the inverse starts a new
// branch: params_version changes exactly at the first tick that moves back.
TEST(Compensator, SwapsParametersOnlyAtAReversalAndWithoutABump) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 300));
  PlanRecorder rec;
  comp.set_trajectory(mem_paper_reference(0.0), 0.0);  // peaks at t = 0.5 s, troughs at 1.0 s
  for (std::int64_t s = 0; s < 12000; ++s) {
    comp.observe({s, 0.0, 0.0});
    MemParams p;
    if (s == 2000) {  // rising
      p.c1 *= 1.2;
      comp.offer_mem_params(p, 5);
    }
    if (s == 6000) {  // falling
      p.c2 *= 0.7;
      comp.offer_mem_params(p, 6);
    }
    if ((s + 1) % 10 == 0) rec.drain(comp);
  }
  const auto& t = rec.ticks();
  std::vector<std::int64_t> changes;
  double max_step = 0.0;
  for (std::size_t i = 2; i < t.size(); ++i) {
    if (t[i].params_version != t[i - 1].params_version) {
      changes.push_back(t[i].seq);
      const double d0 = t[i - 1].y_ref_m - t[i - 2].y_ref_m;
      const double d1 = t[i].y_ref_m - t[i - 1].y_ref_m;
      EXPECT_LT(d0 * d1, 0.0) << "swapped at tick " << t[i].seq << ", not at a reversal";
    }
    if (t[i].seq > 2000) max_step = std::max(max_step, std::abs(t[i].u_ff_V - t[i - 1].u_ff_V));
  }
  // The reference peaks at tick 5000 and troughs at tick 10000; the ticks after move back.
  EXPECT_EQ(changes, (std::vector<std::int64_t>{5001, 10001}));
  EXPECT_EQ(rec.at(5000).params_version, 0);
  EXPECT_EQ(rec.at(5001).params_version, 5);
  EXPECT_EQ(rec.at(10001).params_version, 6);
  EXPECT_EQ(comp.counters().params_swapped, 2u);
  EXPECT_EQ(comp.params_version(), 6);
  EXPECT_EQ(comp.mem_params().c2, MemParams{}.c2 * 0.7);
  EXPECT_LT(max_step, 0.5);  // a smooth 1 Hz sweep of ~+-250 V moves < 0.2 V per tick: no jump
}

// A bridge restart starts a new law with what was in force: the sets (and their version), the
// mode, the reference from its start; what the old law counted stays with the old law.
TEST(Compensator, ARestartedLawKeepsWhatIsInForce) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 300));
  PlanRecorder rec;
  comp.set_trajectory(mem_paper_reference(0.0), 0.0);
  MemParams p;
  p.c1 *= 1.2;
  for (std::int64_t s = 0; s < 6000; ++s) {
    comp.observe({s, 0.0, 0.0});
    if (s == 2000) comp.offer_mem_params(p, 5);  // swapped at the peak, tick 5000
    if ((s + 1) % 10 == 0) rec.drain(comp);
  }
  ASSERT_EQ(comp.params_version(), 5);
  std::string refusal = "stale";
  const Compensator next = comp.restarted(compensator_config(FeedforwardMode::kMem, 300), refusal);
  EXPECT_EQ(refusal, "");
  EXPECT_EQ(next.params_version(), 5);
  EXPECT_EQ(next.mem_params().c1, p.c1);
  EXPECT_EQ(next.mode(), FeedforwardMode::kMem);
  EXPECT_EQ(next.trajectory().amplitude_m, comp.trajectory().amplitude_m);
  EXPECT_EQ(next.trajectory().hold_m, 0.0);
  EXPECT_EQ(next.last_seq(), -1);  // a new numbering: nothing observed yet
  EXPECT_EQ(next.counters().planned, 0u);
}

// A reference the new law's limits no longer allow is not taken again: it holds, saying why.
TEST(Compensator, ARestartedLawHoldsWhereTheReferenceInForceIsInfeasibleNow) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 300));
  comp.set_trajectory(mem_paper_reference(0.0), 0.0);
  CompensatorConfig tight = compensator_config(FeedforwardMode::kMem, 300);
  tight.slew_V_per_s = 100.0;  // the 1 Hz +-250 V sweep needs ~1600 V/s
  std::string refusal;
  const Compensator next = comp.restarted(tight, refusal);
  EXPECT_NE(refusal.find("slew"), std::string::npos) << refusal;
  EXPECT_EQ(next.trajectory().amplitude_m, TrajectorySpec{}.amplitude_m);
}

TEST(Compensator, RefusesInvalidParametersAndKeepsTheOldOnes) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 50));
  MemParams bad;
  bad.c3 = -1.0;
  EXPECT_THROW(comp.offer_mem_params(bad, 2), ParameterError);
  EXPECT_EQ(comp.counters().params_rejected, 1u);
  EXPECT_EQ(comp.counters().params_accepted, 0u);
  EXPECT_EQ(comp.mem_params().c3, MemParams{}.c3);
}

// A scripted session touching every input: samples from a wobbling stage, with a gap and a stall
// longer than the horizon, a trajectory, parameters, experiments (one stopped), mode changes.
// Returns every tick planned, planned `chunk` ticks per plan() call.
struct Session {
  std::vector<CommandTick> ticks;
  CompensatorCounters counters;
};
Session scripted_session(std::size_t chunk) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 300));
  PlanRecorder rec(chunk);
  comp.set_trajectory(mem_paper_reference(0.05, 0.05), kNaN);
  ExperimentSpec sine;
  sine.amplitude_V = 100.0;
  sine.frequency_hz = 20.0;
  sine.duration_s = 0.1;
  ExperimentSpec settle = sine;
  settle.settle = true;
  settle.frequency_hz = 33.0;
  for (std::int64_t k = 0; k < 30000; ++k) {
    const double phase = 0.0007 * static_cast<double>(k);
    MemParams p;
    const std::int64_t step = k / 7000;  // a new set every 0.7 s
    p.c1 *= 1.0 + 0.1 * static_cast<double>(step);
    if (k % 7000 == 3500) comp.offer_mem_params(p, static_cast<std::int32_t>(k / 7000) + 2);
    if (k == 9000) comp.start_experiment(sine);
    if (k == 9001) comp.start_experiment(settle);
    if (k == 15000) comp.set_mode(FeedforwardMode::kPi);
    if (k == 18000) comp.set_mode(FeedforwardMode::kMem);
    if (k == 20000) {
      sine.duration_s = 1.0;
      comp.start_experiment(sine);
    }
    if (k == 20500) comp.stop_experiment();
    if (k == 22000) comp.set_trajectory(mem_paper_reference(0.0, 0.1), comp.loop_time(k) + 0.2);
    const bool stalled = k >= 26000 && k < 26400;  // longer than the horizon: ticks are lost
    if (!stalled && k % 97 != 0) comp.observe({k, 100.0 * std::sin(phase + 0.1), 1e-6 * std::sin(phase)});
    if ((k + 1) % 10 == 0) rec.drain(comp);
  }
  return {rec.ticks(), comp.counters()};
}

// The plan is a function of the inputs, in order: two compensators agree to the bit, and how the
// planning is cut into plan() calls changes nothing.
TEST(Compensator, IsDeterministicAndIndependentOfHowThePlanIsChunked) {
  const Session reference = scripted_session(1000);
  // The session covers what it claims to.
  EXPECT_GT(reference.counters.ticks_behind, 0u);
  EXPECT_GT(reference.counters.gaps, 0u);
  EXPECT_GE(reference.counters.params_swapped, 3u);
  std::size_t experiment_ticks = 0, no_reference = 0;
  for (const CommandTick& t : reference.ticks) {
    experiment_ticks += t.mode == static_cast<std::int8_t>(FeedforwardMode::kExperiment);
    no_reference += std::isnan(t.y_ref_m);
  }
  EXPECT_GT(experiment_ticks, 2500u);
  EXPECT_GT(no_reference, experiment_ticks);  // the hold ticks after each experiment
  for (std::size_t chunk : {1000u, 1u, 7u}) {
    const Session s = scripted_session(chunk);
    ASSERT_EQ(s.ticks.size(), reference.ticks.size()) << "chunk " << chunk;
    for (std::size_t i = 0; i < s.ticks.size(); ++i) {
      ASSERT_TRUE(testing::same_tick(s.ticks[i], reference.ticks[i]))
          << "chunk " << chunk << ", tick " << s.ticks[i].seq;
    }
  }
}

TEST(Compensator, ObserveAndPlanAllocateNothing) {
  Compensator comp(compensator_config(FeedforwardMode::kMem, 300));
  comp.set_trajectory(mem_paper_reference(0.0), 0.0);
  ExperimentSpec e;
  e.duration_s = 0.2;
  comp.start_experiment(e);  // ends, holds, anchors, then tracks: all inside the counted loop
  comp.start_experiment(e);
  MemParams p;
  p.c1 *= 1.1;
  comp.offer_mem_params(p, 2);  // swapped inside the counted loop
  std::vector<CommandTick> out(64);
  std::size_t planned = 0;
  testing::AllocationCounter counter;
  for (std::int64_t k = 0; k < 30000; ++k) {
    if (k % 1000 != 999) comp.observe({k, 0.0, 1e-9 * static_cast<double>(k % 100)});
    while (const std::size_t n = comp.plan(out)) planned += n;
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_GT(planned, 29000u);
  EXPECT_EQ(comp.counters().params_swapped, 1u);
  EXPECT_FALSE(comp.experiment_running());
}

TEST(Compensator, ConfigValidationNamesTheField) {
  CompensatorConfig c = compensator_config(FeedforwardMode::kMem, 0);
  try {
    Compensator comp(c);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "compensator.horizon_s");
  }
  c.horizon_ticks = CompensatorConfig::kMaxHorizonTicks + 1;
  EXPECT_THROW(Compensator{c}, ParameterError);
  c.horizon_ticks = CompensatorConfig::kMaxHorizonTicks;
  EXPECT_NO_THROW(Compensator{c});
  EXPECT_LE(CompensatorConfig::kMaxHorizonTicks, CommandBuffer::kCapacityTicks);  // the bridge can hold it
  c.mode = FeedforwardMode::kExperiment;
  try {
    Compensator comp(c);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "compensator.mode");
  }
  EXPECT_THROW(parse_feedforward_mode("memm"), ParameterError);
  EXPECT_EQ(parse_feedforward_mode("katalenic"), FeedforwardMode::kKatalenic);
  EXPECT_STREQ(to_string(FeedforwardMode::kPi), "pi");
}

}  // namespace
}  // namespace hystloop
