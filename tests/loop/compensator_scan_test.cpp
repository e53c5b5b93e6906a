// The compensator following one axis's share of a multi-axis path (Compensator::take_scan).
#include <gtest/gtest.h>

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
  EXPECT_EQ(loop.comp.counters().trajectories_refused, 1u);
}

TEST(CompensatorScan, AnInfeasibleScanIsRefusedNamingTheAxisAndTheLimit) {
  CompensatorConfig c;  // the real actuator: 5e4 V/s
  c.horizon_ticks = 50;
  CompensatorLoop loop(c);
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

}  // namespace
}  // namespace hystloop
