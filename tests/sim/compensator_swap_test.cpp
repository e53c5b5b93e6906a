// The swap that repairs: a parameter set swapped in at a reversal is re-anchored at the measured
// position of that reversal (which arrives a horizon after the swap was planned), ramped in
// without a step in u or y, and the offset the wrong parameters left is gone. Also a switch of
// model (offer_model) at a reversal, and offer_model's validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "sim/loop_simulation.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

const MemParams kTruth{6.0e-9, 2.0e-12, 1.2};  // a Ramberg-Osgood stage the reference fits in +-250 V

MemParams wrong_params() {
  MemParams m = kTruth;
  m.c1 *= 0.6;
  m.c2 *= 1.8;
  return m;
}

LoopSimulationConfig ro_loop(const MemParams& start) {
  LoopSimulationConfig c;
  c.stage.plant = PlantKind::kRambergOsgood;
  c.stage.ramberg_osgood = kTruth;
  c.stage.noise_rms_m = 0.0;
  c.compensator.mode = FeedforwardMode::kMem;
  c.compensator.models.mem = start;
  return c;
}

void start_reference(LoopSimulation& sim) {
  const TrajectorySpec reference = mem_paper_reference(0.5, 0.5, 0.0);
  sim.compensator().set_trajectory(reference, reference.start_s);
}

struct Steps {
  double du_V = 0.0;  // largest tick-to-tick change of the applied voltage
  double dy_m = 0.0;  // ... and of the true position
};

Steps largest_steps(const std::vector<LoopTick>& h, double from_s, double to_s) {
  Steps s;
  for (std::size_t k = 1; k < h.size(); ++k) {
    if (h[k].t_s < from_s || h[k].t_s >= to_s) continue;
    s.du_V = std::max(s.du_V, std::abs(h[k].u_V - h[k - 1].u_V));
    s.dy_m = std::max(s.dy_m, std::abs(h[k].y_true_m - h[k - 1].y_true_m));
  }
  return s;
}

TEST(CompensatorSwap, ReanchorsAtTheMeasuredReversalWithoutAStepAndTheOffsetIsGone) {
  LoopSimulation sim(ro_loop(wrong_params()));
  start_reference(sim);
  sim.run(3.0);
  const double before = sim.tracking(2.0, 3.0).rms_true_m;
  EXPECT_GT(before, 100e-9);  // the wrong parameters' loop sits off the reference
  sim.compensator().offer_mem_params(kTruth, 2);
  sim.run(3.0);
  const CompensatorCounters& n = sim.compensator().counters();
  EXPECT_EQ(n.params_swapped, 1u);
  EXPECT_EQ(n.reanchors, 1u);
  EXPECT_EQ(n.reanchors_skipped, 0u);
  EXPECT_EQ(n.u_clamped, 0u);
  // The exact model, re-anchored at the measured reversal: no offset left (without the anchor
  // the new parameters would keep the old loop's offset, ~200 nm here).
  EXPECT_LT(sim.tracking(4.5, 6.0).rms_true_m, 1e-11);
  EXPECT_LT(std::abs(sim.compensator().anchor_offset_m()), 1e-6);
  // Bumpless: across the swap (3.5 s) and the ramp after the sample arrives, u and y move no
  // more per tick than the reference makes them move anyway plus the ramp's share of the slew.
  const Steps tracking = largest_steps(sim.history(), 2.0, 3.0);
  const Steps swap = largest_steps(sim.history(), 3.0, 4.5);
  const CompensatorConfig& cc = sim.compensator().config();
  EXPECT_LE(swap.du_V, tracking.du_V + cc.slew_fraction * cc.slew_V_per_s * cc.dt_s);
  EXPECT_LE(swap.du_V, cc.slew_V_per_s * cc.dt_s);
  EXPECT_LE(swap.dy_m, 2.0 * tracking.dy_m);
  for (const LoopTick& t : sim.history()) {
    EXPECT_LE(std::abs(t.u_V), 250.0);
  }
}

TEST(CompensatorSwap, ANewModelTakesOverAtAReversalWithoutAStep) {
  LoopSimulation sim(ro_loop(kTruth));
  start_reference(sim);
  sim.run(3.0);
  ModelParamSet pi;
  pi.kind = ModelKind::pi;
  pi.pi = pi_params_from_mem(kTruth, 15, 250.0);
  sim.compensator().offer_model(pi, 2);
  EXPECT_EQ(sim.compensator().mode(), FeedforwardMode::kMem);  // not before the reversal
  sim.run(3.0);
  EXPECT_EQ(sim.compensator().mode(), FeedforwardMode::kPi);
  EXPECT_EQ(sim.compensator().model_params().kind, ModelKind::pi);
  EXPECT_EQ(sim.compensator().params_version(), 2);
  EXPECT_EQ(sim.compensator().counters().model_switches, 1u);
  const Steps tracking = largest_steps(sim.history(), 2.0, 3.0);
  const Steps swap = largest_steps(sim.history(), 3.0, 4.5);
  const CompensatorConfig& cc = sim.compensator().config();
  EXPECT_LE(swap.du_V, tracking.du_V + cc.slew_fraction * cc.slew_V_per_s * cc.dt_s);
  EXPECT_LE(swap.dy_m, 2.0 * tracking.dy_m);
  // PI-15 approximates the stage's MEM curve to a few nanometres.
  EXPECT_LT(sim.tracking(4.5, 6.0).rms_true_m, 10e-9);
}

TEST(CompensatorSwap, OfferModelValidatesAndCountsRefusals) {
  Compensator c(CompensatorConfig{});
  ModelParamSet bad;
  bad.kind = ModelKind::pi;  // count 0: no operators
  try {
    c.offer_model(bad, 5);
    FAIL() << "accepted an invalid PI set";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field().rfind("pi.", 0), 0u) << e.field();
  }
  bad.kind = ModelKind::mem;
  bad.mem.c1 = std::nan("");
  EXPECT_THROW(c.offer_model(bad, 6), ParameterError);
  EXPECT_EQ(c.counters().params_rejected, 2u);
  EXPECT_FALSE(c.params_pending());
  ModelParamSet good;
  good.kind = ModelKind::linear;
  c.offer_model(good, 7);
  EXPECT_TRUE(c.params_pending());
  EXPECT_EQ(c.counters().params_accepted, 1u);
}

TEST(CompensatorSwap, ConfigRefusesAnInvertedActuatorRange) {
  CompensatorConfig c;
  c.u_min_V = 10.0;
  c.u_max_V = -10.0;
  EXPECT_EQ(testing::refused_field([&] { c.validate(); }), "compensator.u_max_V");
  c = {};
  c.slew_V_per_s = 0.0;
  EXPECT_THROW(c.validate(), ParameterError);
  c = {};
  c.reanchor_ticks = 0;
  EXPECT_THROW(c.validate(), ParameterError);
}

}  // namespace
}  // namespace hystloop
