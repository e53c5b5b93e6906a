// The in-process loop (sim/loop_simulation.hpp) on the series plant: Banning's Table 1 hysteresis,
// then two modes (780 Hz, 2.4 kHz) and 1.5 ticks of input delay, as deploy/config/two-mode/bridge.yaml.
// A 10 Hz sine commanded open loop (feedforward off) runs without a NaN and, far below the modes,
// moves the stage as Banning's stage with the same hysteresis does: both stages have unit DC gain,
// so at 10 Hz they differ by the delay's and the modes' phase, about 1 % of the swing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sim/loop_simulation.hpp"
#include "sim/multi_axis_loop_simulation.hpp"

namespace hystloop {
namespace {

std::vector<LoopTick> sine_through_the_loop(PlantKind plant) {
  LoopSimulationConfig c;
  c.stage.plant = plant;
  c.stage.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 150e-6);
  c.stage.noise_rms_m = 1e-9;
  c.compensator.mode = FeedforwardMode::kOff;
  LoopSimulation sim(c);
  ExperimentSpec sine;
  sine.amplitude_V = 100.0;
  sine.frequency_hz = 10.0;
  sine.duration_s = 1.0;
  sim.compensator().start_experiment(sine);
  sim.run(1.01);
  return sim.history();
}

TEST(SeriesPlantLoop, ATenHertzSineRunsAndMovesTheStageAsBanningsDoes) {
  const std::vector<LoopTick> series = sine_through_the_loop(PlantKind::kSeries);
  const std::vector<LoopTick> banning = sine_through_the_loop(PlantKind::kBanning);
  ASSERT_EQ(series.size(), banning.size());
  double swing = 0.0, diff2 = 0.0, y2 = 0.0, u_max = 0.0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    ASSERT_TRUE(std::isfinite(series[k].y_m)) << k;
    ASSERT_TRUE(std::isfinite(series[k].y_true_m)) << k;
    EXPECT_EQ(series[k].u_V, banning[k].u_V) << k;  // open loop: the same commands
    swing = std::max(swing, std::abs(series[k].y_true_m));
    u_max = std::max(u_max, std::abs(series[k].u_V));
    diff2 += std::pow(series[k].y_true_m - banning[k].y_true_m, 2);
    y2 += std::pow(banning[k].y_true_m, 2);
  }
  EXPECT_GT(u_max, 99.0);
  // Coleman-Hodgdon's loop centres lie on w = a u (Table 1: a = 8.58 nm/V): ~0.86 um at 100 V.
  EXPECT_NEAR(swing, 8.58e-9 * 100.0, 0.3 * 8.58e-9 * 100.0);
  const double relative = std::sqrt(diff2 / y2);
  std::printf("series vs Banning at 10 Hz: %.3g %% RMS of the swing, peak %.4g um\n", 100.0 * relative, swing * 1e6);
  EXPECT_LT(relative, 0.03);
}

// The loops sample the series plant at their own tick: a loop at 5 kHz runs it at 5 kHz (a stage
// sampled at another tick would return NaN), one axis or two.
TEST(SeriesPlantLoop, IsSampledAtTheLoopsTick) {
  LoopSimulationConfig c;
  c.stage.plant = PlantKind::kSeries;
  c.stage.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 150e-6);
  c.compensator.mode = FeedforwardMode::kOff;
  c.compensator.dt_s = 2e-4;
  c.compensator.learning.cutoff_hz = 1000.0;  // below the 5 kHz loop's bound
  LoopSimulation sim(c);
  ExperimentSpec sine;
  sine.amplitude_V = 50.0;
  sine.duration_s = 0.2;
  sim.compensator().start_experiment(sine);
  sim.run(0.2);
  ASSERT_FALSE(sim.history().empty());
  for (const LoopTick& t : sim.history()) ASSERT_TRUE(std::isfinite(t.y_m)) << t.k;

  MultiAxisLoopConfig xy;
  for (SimulatedStageConfig& axis : xy.stage.axis) {
    axis.plant = PlantKind::kSeries;
    axis.linear = c.stage.linear;
  }
  for (CompensatorConfig& comp : xy.compensator) {
    comp.mode = FeedforwardMode::kOff;
    comp.dt_s = 2e-4;
    comp.learning.cutoff_hz = 1000.0;
  }
  MultiAxisLoopSimulation loop(xy);
  bool finite = true;
  loop.run(0.05, [&](const MultiAxisTick& t) {
    for (int a = 0; a < loop.axes(); ++a) finite = finite && std::isfinite(t.y_m[static_cast<std::size_t>(a)]);
  });
  EXPECT_TRUE(finite);
}

}  // namespace
}  // namespace hystloop
