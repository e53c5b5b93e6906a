// The compensator following one axis's share of a multi-axis path (Compensator::take_scan).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "compensator_rig.hpp"
#include "loop/compensator.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using testing::compensator_config;
using testing::CompensatorLoop;
using testing::kDt;
using testing::refused_field;

// 8 lines of 1 um at 20 lines/s, 1 um high, starting at 0.5 s.
RasterSpec raster() {
  return {.fast_axis = 0,
          .slow_axis = 1,
          .width_m = 1e-6,
          .height_m = 1e-6,
          .lines = 8,
          .line_rate_hz = 20.0,
          .corner_s = 2e-3,
          .start_s = 0.5};
}

// The compensator's defaults: the real actuator's range and slew limit (5e4 V/s).
CompensatorConfig real_actuator() {
  CompensatorConfig c;
  c.horizon_ticks = 50;
  return c;
}

TEST(CompensatorScan, TheServoTracksThePathsAxisAndTheInverseAimsAtTheShare) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  const AxisVector row(-0.03, 1.0, 0.0);  // y's row of C^-1 for x moving y by 3 %
  const ScanShare share(raster(), 1, row);
  loop.comp.take_scan(share, 0.2);
  ASSERT_NE(loop.comp.scan(), nullptr);
  loop.run(10000);  // through the lines (0.5 s to 0.9 s) and after
  for (std::int64_t k = 3000; k < 10000; k += 7) {
    const double t = static_cast<double>(k) * kDt;
    const CommandTick& c = loop.plan.at(k);
    if (t < 0.5) continue;
    EXPECT_NEAR(c.y_ref_m, evaluate(raster(), t)[1], 1e-15) << t;  // the sensor's reference
    // The plant is the rig's MEM model with the compensator's own parameters: what it reached is
    // what the inverse aimed at, the share w_y = r_y - 0.03 r_x (once the decoupling has faded in).
    EXPECT_NEAR(loop.y_measured[static_cast<std::size_t>(k)], share.at(t), 1e-12) << t;
  }
}

TEST(CompensatorScan, BeforeTheApproachTheAxisHoldsAndTheDecouplingFadesIn) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  const ScanShare share(raster(), 1, AxisVector(-0.03, 1.0, 0.0));
  loop.comp.take_scan(share, 0.2);
  loop.run(5000);
  // Held where it was (0 m) until the approach begins at 0.3 s.
  EXPECT_EQ(loop.plan.at(2000).y_ref_m, 0.0);
  EXPECT_NEAR(loop.y_measured[2000], 0.0, 1e-15);
  // At the start the axis is at the path's first point, x's share added: -0.5 um + 0.03 x 0.5 um.
  EXPECT_NEAR(loop.plan.at(5000).y_ref_m, -0.5e-6, 1e-15);
  EXPECT_NEAR(loop.y_measured[4999], share.at(0.5), 1e-10);
  // No step anywhere: the largest tick-to-tick move is the lines' own.
  double largest = 0.0;
  for (std::size_t k = 101; k < loop.y_measured.size(); ++k)
    largest = std::max(largest, std::abs(loop.y_measured[k] - loop.y_measured[k - 1]));
  EXPECT_LT(largest, 1e-9);
}

TEST(CompensatorScan, AStartTheApproachCannotReachIsRefusedAndNothingChanges) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(4000);  // the plan is at 0.405 s: the approach of 0.2 s cannot end at 0.5 s
  const ScanShare share(raster(), 0, AxisVector(1.0, 0.0, 0.0));
  EXPECT_EQ(refused_field([&] { loop.comp.take_scan(share, 0.2); }), "scan.start_s");
  EXPECT_EQ(loop.comp.scan(), nullptr);
  EXPECT_EQ(loop.comp.counters().plan_refusals, 1u);
}

TEST(CompensatorScan, AnInfeasibleScanIsRefusedNamingTheAxisAndTheLimit) {
  CompensatorLoop loop(real_actuator());
  loop.run(100);
  RasterSpec fast = raster();
  fast.width_m = 20e-6;  // 20 um lines at 20 lines/s: 4e-4 m/s, about 6e4 V/s
  const ScanShare share(fast, 0, AxisVector(1.0, 0.0, 0.0));
  try {
    loop.comp.take_scan(share, 0.2);
    FAIL() << "taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "scan");
    const std::string what = e.what();
    EXPECT_NE(what.find("axis x"), std::string::npos) << what;
    EXPECT_NE(what.find("slew"), std::string::npos) << what;
  }
  EXPECT_EQ(loop.comp.scan(), nullptr);
}

TEST(CompensatorScan, ANewTrajectoryEndsTheScan) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  loop.comp.take_scan(ScanShare(raster(), 0, AxisVector(1.0, 0.0, 0.0)), 0.2);
  loop.run(5500);
  TrajectorySpec hold;
  hold.blend_s = 0.1;
  loop.comp.set_trajectory(hold, std::nan(""));
  EXPECT_EQ(loop.comp.scan(), nullptr);
  loop.run(3000);
  EXPECT_NEAR(loop.plan.at(8500).y_ref_m, 0.0, 1e-15);  // faded out into the hold at 0 m
}

// A finished decoupled scan still holds its decoupling term (y's aim is r_y - 0.03 r_x at the
// end): what replaces it fades that out over its approach, without a step of the position.
TEST(CompensatorScan, ReplacingAFinishedDecoupledScanFadesItsDecouplingOut) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  loop.comp.take_scan(ScanShare(raster(), 1, AxisVector(-0.03, 1.0, 0.0)), 0.2);
  loop.run(9500);  // the lines end at 0.9 s
  TrajectorySpec hold;
  hold.blend_s = 0.1;
  loop.comp.set_trajectory(hold, std::nan(""));
  loop.run(3000);
  double largest = 0.0;
  for (std::size_t k = 9050; k < loop.y_measured.size(); ++k)
    largest = std::max(largest, std::abs(loop.y_measured[k] - loop.y_measured[k - 1]));
  // The approach to 0 m moves up to 1.1 nm per tick; a dropped term would step by 15 nm (0.03 x the
  // fast axis's 0.5 um) in one.
  EXPECT_LT(largest, 2e-9);
  EXPECT_NEAR(loop.y_measured.back(), 0.0, 1e-12);
}

TEST(CompensatorScan, APathThatEndsTooFarAheadToBeCheckedWholeIsRefused) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  RasterSpec late = raster();
  late.start_s = 25.0;  // ends at 25.4 s: beyond the 20 s the dry run covers
  EXPECT_EQ(refused_field([&] { loop.comp.take_scan(ScanShare(late, 0, AxisVector(1.0, 0.0, 0.0)), 0.2); }), "scan");
  EXPECT_EQ(loop.comp.scan(), nullptr);
}

TEST(CompensatorScan, AScanIsNotTakenWhileAnExperimentRunsOrWaits) {
  CompensatorLoop loop(compensator_config(FeedforwardMode::kMem, 50));
  loop.run(100);
  ExperimentSpec e;
  e.amplitude_V = 10.0;
  e.duration_s = 0.2;
  loop.comp.start_experiment(e);
  RasterSpec r = raster();
  r.start_s = 1.0;
  EXPECT_EQ(refused_field([&] { loop.comp.take_scan(ScanShare(r, 0, AxisVector(1.0, 0.0, 0.0)), 0.2); }), "scan");
  EXPECT_EQ(loop.comp.scan(), nullptr);
  loop.run(4000);  // the experiment is over and the plan anchored: now it is taken
  loop.comp.take_scan(ScanShare(r, 0, AxisVector(1.0, 0.0, 0.0)), 0.2);
  EXPECT_NE(loop.comp.scan(), nullptr);
}

TEST(CompensatorScan, AParameterSetUnderWhichTheRestOfTheScanWouldLeaveTheLimitsIsRefused) {
  CompensatorLoop loop(real_actuator());
  loop.run(100);
  RasterSpec fast = raster();
  fast.width_m = 3e-6;  // 3 um lines at 50 lines/s: about half the slew limit
  fast.line_rate_hz = 50.0;
  loop.comp.take_scan(ScanShare(fast, 0, AxisVector(1.0, 0.0, 0.0)), 0.2);
  loop.run(5500);  // on the lines
  MemParams soft = loop.comp.mem_params();
  soft.c1 *= 0.4;  // a stage 2.5 times softer: the same lines need 2.5 times the voltage rate
  soft.c2 *= 0.4;
  EXPECT_EQ(refused_field([&] { loop.comp.offer_mem_params(soft, 2); }), "params");
  EXPECT_FALSE(loop.comp.params_pending());
  MemParams stiff = loop.comp.mem_params();
  stiff.c1 *= 1.1;
  stiff.c2 *= 1.1;
  loop.comp.offer_mem_params(stiff, 3);  // needs less: taken
  EXPECT_TRUE(loop.comp.params_pending());
}

}  // namespace
}  // namespace hystloop
