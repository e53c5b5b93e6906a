// The simulated stage's gain drift (common/loop/simulated_stage.hpp): flat before drift_start_s,
// a straight ramp to 1 + drift_fraction over drift_duration_s, flat after; the position scales
// with it. Values derived by hand from the config: scale(t) = 1 + f clamp((t - t0) / T, 0, 1).
#include "loop/simulated_stage.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

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

}  // namespace
}  // namespace hystloop
