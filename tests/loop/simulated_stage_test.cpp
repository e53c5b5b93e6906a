// The simulated stage's gain drift (common/loop/simulated_stage.hpp): flat before drift_start_s,
// a straight ramp to 1 + drift_fraction over drift_duration_s, flat after; the position scales
// with it. Values derived by hand from the config: scale(t) = 1 + f clamp((t - t0) / T, 0, 1).
// The series plant: exactly HysteresisPlant then LinearStageSimulator, stepped by hand; its noise
// the seed's; its refusals named as the bridge's keys.
#include "loop/simulated_stage.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

SimulatedStageConfig drifting(PlantKind plant, double fraction) {
  SimulatedStageConfig c;
  c.plant = plant;
  c.ramberg_osgood = MemParams::paper_like();
  c.noise_rms_m = 0.0;
  c.drift_fraction = fraction;
  c.drift_start_s = 10.0;
  c.drift_duration_s = 40.0;
  return c;
}

TEST(SimulatedStageDrift, GainRampsLinearlyBetweenStartAndEnd) {
  for (PlantKind plant : {PlantKind::kBanning, PlantKind::kRambergOsgood}) {
    for (double f : {0.1, -0.2}) {
      SimulatedStage s(drifting(plant, f));
      // (t, expected scale): before, at the start, a quarter, half, the end, long after.
      const double points[][2] = {{0.0, 1.0},          {9.999, 1.0},    {10.0, 1.0},      {20.0, 1.0 + f / 4},
                                  {30.0, 1.0 + f / 2}, {50.0, 1.0 + f}, {3600.0, 1.0 + f}};
      for (const auto& p : points) {
        s.step(1.0, p[0], 1e-4);
        EXPECT_NEAR(s.gain_scale(), p[1], 1e-12) << "plant " << static_cast<int>(plant) << " f " << f << " t " << p[0];
      }
    }
  }
}

TEST(SimulatedStageDrift, PositionScalesWithTheGain) {
  // Ramberg-Osgood plant (static): the drifting stage's position is the steady one's times scale.
  SimulatedStage steady(drifting(PlantKind::kRambergOsgood, 0.0));
  SimulatedStage warm(drifting(PlantKind::kRambergOsgood, 0.1));
  for (int k = 0; k < 600; ++k) {
    const double t = 0.1 * k;  // 0 .. 60 s
    const double u = 100.0 * std::sin(0.3 * t);
    const double y0 = steady.step(u, t, 0.1), y1 = warm.step(u, t, 0.1);
    const double scale = 1.0 + 0.1 * std::clamp((t - 10.0) / 40.0, 0.0, 1.0);
    EXPECT_NEAR(y1, scale * y0, 1e-12 * std::abs(y0) + 1e-24) << t;
  }
}

TEST(SimulatedStageDrift, RefusesADriftOutsideItsDomain) {
  SimulatedStageConfig c = drifting(PlantKind::kBanning, 0.1);
  c.drift_duration_s = 0.0;
  try {
    SimulatedStage s(c);
    ADD_FAILURE() << "drift_duration_s = 0 was accepted";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "bridge.drift_duration_s");
  }
  c = drifting(PlantKind::kBanning, -0.6);  // the gain would fall by more than half
  EXPECT_THROW(SimulatedStage{c}, ParameterError);
}

// Banning's Table 1 hysteresis, then modes at 780 Hz and 2.4 kHz, then 1.5 ticks of delay: the
// deploy/config/two-mode stage.
SimulatedStageConfig two_mode(HysteresisPlantKind kind = HysteresisPlantKind::coleman_hodgdon) {
  SimulatedStageConfig c;
  c.plant = PlantKind::kSeries;
  c.hysteresis.kind = kind;
  c.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 150e-6);
  c.tick_s = 1e-4;
  c.noise_rms_m = 0.0;
  return c;
}

double sweep_u(int k) { return 200.0 * std::sin(2.0 * std::numbers::pi * 37.0 * k * 1e-4) * std::exp(-k * 2e-4); }

TEST(SimulatedStageSeries, IsTheHysteresisThenTheLinearStageBitForBit) {
  for (HysteresisPlantKind kind :
       {HysteresisPlantKind::coleman_hodgdon, HysteresisPlantKind::mem, HysteresisPlantKind::pi,
        HysteresisPlantKind::katalenic, HysteresisPlantKind::bouc_wen, HysteresisPlantKind::linear}) {
    const SimulatedStageConfig c = two_mode(kind);
    SimulatedStage stage(c);
    HysteresisPlant h(c.hysteresis);
    LinearStageSimulator l(discretise(c.linear, c.tick_s));
    HysteresisPlant at_rest = h;
    l.reset(at_rest.step(0.0, c.tick_s));
    for (int k = 0; k < 3000; ++k) {
      const double u = sweep_u(k);
      const double expected = l.step(h.step(u, c.tick_s));
      const double y = stage.step(u, k * 1e-4, 1e-4);
      ASSERT_EQ(y, expected) << to_string(kind) << " tick " << k;
      ASSERT_EQ(stage.true_position_m(), expected);
    }
  }
}

TEST(SimulatedStageSeries, TheDriftScalesTheHysteresisOutput) {
  SimulatedStageConfig c = two_mode();
  c.drift_fraction = 0.1;
  c.drift_start_s = 0.0;
  c.drift_duration_s = 0.2;
  SimulatedStage stage(c);
  HysteresisPlant h(c.hysteresis);
  LinearStageSimulator l(discretise(c.linear, c.tick_s));
  for (int k = 0; k < 3000; ++k) {
    const double t = k * 1e-4;
    const double scale = 1.0 + 0.1 * std::clamp(t / 0.2, 0.0, 1.0);
    const double u = sweep_u(k);
    ASSERT_EQ(stage.step(u, t, 1e-4), l.step(scale * h.step(u, c.tick_s))) << k;
  }
}

TEST(SimulatedStageSeries, NoiseIsTheSeedsWhiteNoiseOnTheTruePosition) {
  SimulatedStageConfig c = two_mode();
  c.noise_rms_m = 1e-9;
  c.seed = 7;
  SimulatedStage stage(c);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-9);
  for (int k = 0; k < 1000; ++k) {
    const double y = stage.step(sweep_u(k), k * 1e-4, 1e-4);
    ASSERT_EQ(y, stage.true_position_m() + noise(rng)) << k;
  }
}

TEST(SimulatedStageSeries, HasUnitStageGainAtDcAndTheDelay) {
  SimulatedStageConfig c = two_mode(HysteresisPlantKind::linear);
  SimulatedStage stage(c);
  const double w = c.hysteresis.linear.gain * 100.0 + c.hysteresis.linear.offset;
  // 1.5 ticks of delay: the first tick does not move, the second sees half of it.
  const double y0 = stage.step(0.0, 0.0, 1e-4);
  EXPECT_NEAR(stage.step(100.0, 1e-4, 1e-4), y0, 1e-12 * std::abs(w));
  double y = 0.0;
  for (int k = 2; k < 20000; ++k) y = stage.step(100.0, k * 1e-4, 1e-4);
  EXPECT_NEAR(y, w, 1e-9 * std::abs(w));
}

TEST(SimulatedStageSeries, RefusesAnotherTickAndNonFiniteInputWithNaN) {
  SimulatedStage stage(two_mode());
  const double y1 = stage.step(50.0, 0.0, 1e-4);
  EXPECT_TRUE(std::isnan(stage.step(50.0, 1e-4, 2e-4)));
  EXPECT_TRUE(std::isnan(stage.step(std::numeric_limits<double>::quiet_NaN(), 1e-4, 1e-4)));
  // Neither moved the state: the next tick is the one a stage never refused gives.
  SimulatedStage fresh(two_mode());
  EXPECT_EQ(fresh.step(50.0, 0.0, 1e-4), y1);
  EXPECT_EQ(stage.step(60.0, 1e-4, 1e-4), fresh.step(60.0, 1e-4, 1e-4));
}

TEST(SimulatedStageSeries, StepsWithoutAllocating) {
  for (HysteresisPlantKind kind :
       {HysteresisPlantKind::coleman_hodgdon, HysteresisPlantKind::pi, HysteresisPlantKind::bouc_wen}) {
    SimulatedStageConfig c = two_mode(kind);
    c.noise_rms_m = 1e-9;
    SimulatedStage stage(c);
    double sum = 0.0;
    const testing::AllocationCounter counter;
    for (int k = 0; k < 2000; ++k) sum += stage.step(sweep_u(k), k * 1e-4, 1e-4);
    EXPECT_EQ(counter.allocations(), 0U) << to_string(kind);
    EXPECT_TRUE(std::isfinite(sum));
  }
}

std::string refused_field(const SimulatedStageConfig& c) {
  try {
    SimulatedStage s(c);
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "accepted";
}

TEST(SimulatedStageSeries, RefusalsNameTheBridgesKey) {
  SimulatedStageConfig c = two_mode(HysteresisPlantKind::bouc_wen);
  c.hysteresis.bouc_wen.gamma = 1.0;  // > beta
  EXPECT_EQ(refused_field(c), "plant.hysteresis.bouc_wen.gamma");
  c = two_mode();
  c.linear.delay_s = -1e-4;
  EXPECT_EQ(refused_field(c), "plant.stage.delay_s");
  c = two_mode();
  c.linear = LinearStageSpec::zero_pole({}, {{10.0, 100.0}});  // a pole in the right half plane
  EXPECT_TRUE(refused_field(c).starts_with("plant.stage.poles")) << refused_field(c);
  c = two_mode();
  c.tick_s = 0.0;
  EXPECT_EQ(refused_field(c), "tick_s");
  // The other plants never look at the series plant's fields.
  c.plant = PlantKind::kBanning;
  EXPECT_EQ(refused_field(c), "accepted");
  EXPECT_EQ(parse_plant_kind("series"), PlantKind::kSeries);
}

}  // namespace
}  // namespace hystloop
