// The bridge's stop: on every stop the bridge disarms BridgeCore and lets it
// ramp to actuator.safe_u_V before the real-time thread ends. This is that path, with time as
// an argument: from anywhere in the range, armed, the ramp reaches the safe voltage exactly within
// ceil(|u - safe| / (rate * dt)) ticks, rate = min(safe_ramp, slew), and no tick steps further.
#include "loop/bridge_core.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "bridge_test_rig.hpp"

namespace hystloop {
namespace {

using testing::command;
using testing::kDt;

struct StopRun {
  double u_before_V = 0.0;   // applied at the last armed tick
  std::int64_t ticks = 0;    // disarmed ticks until the safe voltage was applied (inclusive)
  double max_step_V = 0.0;   // largest |du| over the ramp
  bool flagged_safe = true;  // every ramp tick carried SAFE_STATE
  bool stayed = true;        // and the voltage stayed there afterwards
};

// Drives an armed core to `u_V` (commands every tick: the slew limit takes it there), keeps
// commands flowing (a live compensator), disarms, and ticks until the safe voltage is applied.
StopRun stop_from(const ActuatorLimits& limits, double u_V) {
  auto core = std::make_unique<BridgeCore>(limits, FeedbackGains{}, kDt);
  std::int64_t k = 0;
  core->arm(0);
  for (; k < 2000; ++k) {
    core->submit(command(k, u_V));
    core->tick(k, 0.0);
  }
  StopRun run;
  run.u_before_V = core->last_applied_V();
  core->disarm();
  double prev = run.u_before_V;
  const std::int64_t limit = 10'000'000;
  for (; run.ticks < limit; ++k) {
    core->submit(command(k, u_V));  // still arriving: not applied once disarmed
    const BridgeTick t = core->tick(k, 0.0);
    ++run.ticks;
    run.max_step_V = std::max(run.max_step_V, std::abs(t.u_applied_V - prev));
    run.flagged_safe = run.flagged_safe && (t.flags & sample_flags::kSafeState) != 0;
    prev = t.u_applied_V;
    if (t.u_applied_V == limits.safe_u_V) break;
  }
  for (int i = 0; i < 1000; ++i, ++k) {
    core->submit(command(k, u_V));
    run.stayed = run.stayed && core->tick(k, 0.0).u_applied_V == limits.safe_u_V;
  }
  return run;
}

// A step measured as the difference of two applied voltages carries their rounding (an ulp of
// 250 V is 6e-14 V): the limits are checked to 1e-12 of a step, as in bridge_core_test.
constexpr double kRounding = 1 + 1e-12;

std::int64_t bound_ticks(const ActuatorLimits& limits, double from_V) {
  const double rate = std::min(limits.safe_ramp_V_per_s, limits.slew_V_per_s);
  return static_cast<std::int64_t>(std::ceil(std::abs(from_V - limits.safe_u_V) / (rate * kDt)));
}

TEST(BridgeStop, RampsFromEitherEndOfTheRangeWithinTheBound) {
  const ActuatorLimits limits;  // the product's defaults: 1e3 V/s ramp, 5e4 V/s slew, safe 0 V
  for (const double u : {250.0, -250.0}) {
    const StopRun run = stop_from(limits, u);
    ASSERT_EQ(run.u_before_V, u);
    EXPECT_LE(run.ticks, bound_ticks(limits, u)) << "from " << u << " V";
    EXPECT_EQ(bound_ticks(limits, u), 2500);  // 0.25 s at 10 kHz
    EXPECT_LE(run.max_step_V, limits.safe_ramp_V_per_s * kDt * kRounding) << "from " << u << " V";
    EXPECT_TRUE(run.flagged_safe);
    EXPECT_TRUE(run.stayed);
    EXPECT_NEAR(limits.longest_safe_ramp_s(), 0.25, 1e-12);
  }
}

TEST(BridgeStop, NeverRampsFasterThanTheSlewLimit) {
  ActuatorLimits limits;
  limits.safe_ramp_V_per_s = 1e6;  // faster than the slew limit: the slew limit wins
  limits.slew_V_per_s = 2e4;       // 2 V per tick
  for (const double u : {250.0, -250.0, 37.3}) {
    const StopRun run = stop_from(limits, u);
    ASSERT_EQ(run.u_before_V, u);
    EXPECT_LE(run.ticks, bound_ticks(limits, u)) << "from " << u << " V";
    EXPECT_LE(run.max_step_V, limits.slew_V_per_s * kDt * kRounding) << "from " << u << " V";
    EXPECT_TRUE(run.flagged_safe);
    EXPECT_TRUE(run.stayed);
  }
  EXPECT_NEAR(limits.longest_safe_ramp_s(), 250.0 / 2e4, 1e-12);
}

TEST(BridgeStop, ReachesANonZeroSafeVoltageExactlyFromAwkwardStarts) {
  ActuatorLimits limits;
  limits.safe_u_V = 12.5;
  limits.safe_ramp_V_per_s = 777.0;  // steps that do not divide the distance
  for (const double u : {250.0, -250.0, 12.5, 12.5 + 1e-7, -0.3}) {
    const StopRun run = stop_from(limits, u);
    ASSERT_EQ(run.u_before_V, u);
    EXPECT_LE(run.ticks, std::max<std::int64_t>(1, bound_ticks(limits, u))) << "from " << u << " V";
    EXPECT_LE(run.max_step_V, limits.safe_ramp_V_per_s * kDt * kRounding) << "from " << u << " V";
    EXPECT_TRUE(run.flagged_safe);
    EXPECT_TRUE(run.stayed);
  }
  // The longest ramp starts at the range's end farthest from the safe voltage.
  EXPECT_NEAR(limits.longest_safe_ramp_s(), (12.5 + 250.0) / 777.0, 1e-12);
}

}  // namespace
}  // namespace hystloop
