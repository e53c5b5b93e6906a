// A raster on the simulated XY stage (sim/raster_experiment.hpp), in process: 1 um x 1 um at a
// 50 Hz line rate, 64 lines, x coupled into y by 3 %, per axis the loop of a line-rate scan (the
// identified model, the stage's inverse, the servo). The figures are docs/TRACKING.md's
// (bench/raster_table prints them and draws the error maps). The runs are deterministic (seeded
// sensor noise), so the comparisons between them are exact, not statistical.
#include "sim/raster_experiment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace hystloop {
namespace {

class Raster : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { models_ = identify_for_scan(TrackingExperiment{}, 0.5e-6); }
  static IdentifiedModels models_;
  const TrackingExperiment experiment_{};  // Banning's stage, 1 nm sensor noise per axis
};
IdentifiedModels Raster::models_;

TEST_F(Raster, MeetsTheTargetsWithTheCouplingDecoupled) {
  ASSERT_FALSE(models_.ranking.empty());
  RasterOptions o;
  const RasterRun on = run_raster(experiment_, models_, o);
  ASSERT_FALSE(on.refused) << on.reason;
  EXPECT_EQ(on.t_s.size(), 12800u);         // 64 lines at 50 Hz: 1.28 s of ticks
  EXPECT_LE(on.stats[0].rms_true_m, 2e-9);  // fast axis
  EXPECT_LE(on.stats[1].rms_true_m, 1e-9);  // slow axis
  EXPECT_EQ(on.clamped_ticks, 0u);
  EXPECT_EQ(on.stage_trips, 0u);

  o.learning = true;
  const RasterRun learned = run_raster(experiment_, models_, o);
  ASSERT_FALSE(learned.refused) << learned.reason;
  EXPECT_LE(learned.stats[0].rms_true_m, 1e-9);
  EXPECT_LE(learned.stats[1].rms_true_m, 1e-9);
  EXPECT_EQ(learned.clamped_ticks, 0u);
}

TEST_F(Raster, WithoutDecouplingTheSlowAxisCarriesTheCoupling) {
  RasterOptions o;
  const RasterRun on = run_raster(experiment_, models_, o);
  o.decouple = false;
  const RasterRun off = run_raster(experiment_, models_, o);
  ASSERT_FALSE(on.refused || off.refused) << on.reason << off.reason;
  // The servo rejects most of 3 % of a 50 Hz line (a 30 nm triangle), not all of it.
  EXPECT_GT(off.stats[1].rms_true_m, 1.2 * on.stats[1].rms_true_m);
  EXPECT_NEAR(off.stats[0].rms_true_m, on.stats[0].rms_true_m, 1e-15);  // x is coupled into y, not back
  // Feedforward alone (no servo), the coupling is the slow axis's error: a triangle of 3 % of the
  // line's 1 um, 8.7 nm RMS, on top of the axis's own.
  o.loop.servo = false;
  const RasterRun bare = run_raster(experiment_, models_, o);
  ASSERT_FALSE(bare.refused) << bare.reason;
  EXPECT_GT(bare.stats[1].rms_true_m, 8e-9);
}

TEST_F(Raster, TheCouplingIdentifiedOnTheStageDecouplesItsRaster) {
  RasterOptions o;
  const CouplingFitResult fit = identify_coupling(experiment_, models_, o);
  ASSERT_TRUE(fit.ok()) << fit.reason;
  const AxisMatrix truth = flexure_stage(2, o.coupling).coupling.matrix();
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      if (i == j) continue;
      EXPECT_GT(fit.standard_error(j, i), 0.0);
      EXPECT_LT(std::abs(fit.estimate(j, i) - truth(j, i)), 4.0 * fit.standard_error(j, i))
          << "C(" << j << "," << i << ") = " << fit.estimate(j, i) << " +- " << fit.standard_error(j, i);
    }
  }
  o.identified_decoupling = true;
  const RasterRun run = run_raster(experiment_, models_, o);
  ASSERT_FALSE(run.refused) << run.reason;
  ASSERT_TRUE(run.coupling_fit && run.coupling_fit->ok());
  std::printf("identified x->y %.5f +- %.1e, y->x %.5f; raster with it: x %.3f nm, y %.3f nm\n", fit.estimate(1, 0),
              fit.standard_error(1, 0), fit.estimate(0, 1), run.stats[0].rms_true_m * 1e9,
              run.stats[1].rms_true_m * 1e9);
  EXPECT_LE(run.stats[0].rms_true_m, 2e-9);
  EXPECT_LE(run.stats[1].rms_true_m, 1e-9);
  EXPECT_EQ(run.clamped_ticks, 0u);
}

TEST_F(Raster, AnAxisCountTheDecouplingDoesNotMatchIsRefused) {
  MultiAxisLoopConfig c;
  MultiAxisLoopSimulation sim(c);
  sim.run(0.01);
  RasterSpec r;
  r.width_m = r.height_m = 1e-6;
  r.lines = 8;
  r.line_rate_hz = 10.0;
  r.corner_s = 2e-3;
  r.start_s = 1.0;
  try {
    sim.take_path(r, AxisCoupling::identity(3), 0.2);
    FAIL() << "a 3-axis decoupling taken by a 2-axis stage";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "decoupling");
    EXPECT_NE(std::string(e.what()).find("is for 3 axes, the stage has 2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(sim.compensator(0).scan(), nullptr);
  EXPECT_EQ(sim.compensator(1).scan(), nullptr);
}

}  // namespace
}  // namespace hystloop

namespace hystloop {
namespace {

TEST_F(Raster, ALissajousFigureIsTrackedOnBothAxes) {
  LissajousOptions o;  // 0.5 um at 50 Hz on x, 48 Hz on y, one second
  const LissajousRun on = run_lissajous(experiment_, models_, o);
  ASSERT_FALSE(on.refused) << on.reason;
  o.decouple = false;
  const LissajousRun off = run_lissajous(experiment_, models_, o);
  ASSERT_FALSE(off.refused) << off.reason;
  std::printf("lissajous: x %.3f / %.3f nm, y %.3f / %.3f nm (decoupled / coupled)\n", on.stats[0].rms_true_m * 1e9,
              off.stats[0].rms_true_m * 1e9, on.stats[1].rms_true_m * 1e9, off.stats[1].rms_true_m * 1e9);
  EXPECT_EQ(on.t_s.size(), 10000u);
  EXPECT_LE(on.stats[0].rms_true_m, 2e-9);
  EXPECT_LE(on.stats[1].rms_true_m, 2e-9);
  EXPECT_EQ(on.clamped_ticks, 0u);
}

TEST(MultiAxisLoop, OneAxisLosingItsCommandsTakesTheWholeStageToTheSafeStateOnOneTick) {
  MultiAxisLoopSimulation sim(MultiAxisLoopConfig{});
  sim.run(0.1);
  ASSERT_TRUE(sim.bridge().armed());
  sim.drop_commands(1, true);  // y's commands stop arriving; x's keep coming
  std::int64_t first_safe[2] = {-1, -1};
  sim.run(0.2, [&](const MultiAxisTick& t) {
    for (std::size_t i = 0; i < 2; ++i) {
      if ((t.flags[i] & sample_flags::kSafeState) != 0 && first_safe[i] < 0) first_safe[i] = t.k;
    }
  });
  EXPECT_GE(first_safe[1], 0);
  EXPECT_EQ(first_safe[0], first_safe[1]);
  EXPECT_EQ(sim.bridge().stage_trips(), 1u);
  EXPECT_EQ(sim.bridge().tripped_by(), 1);
  EXPECT_FALSE(sim.bridge().axis(0).armed());
}

}  // namespace
}  // namespace hystloop
