// The bridge of a stage of several axes: one safe state for the whole stage.
#include "loop/multi_axis_bridge.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "support/refusal.hpp"

namespace hystloop {
namespace {

using testing::refused_field;

constexpr double kDt = 1e-4;

MultiAxisBridge two_axes(ActuatorLimits y_limits = {}) {
  const std::array<ActuatorLimits, 2> limits{ActuatorLimits{}, y_limits};
  const std::array<FeedbackGains, 2> servo{};
  return MultiAxisBridge(2, limits, servo, kDt);
}

TEST(MultiAxisBridge, OneAxisWithoutCommandsTakesEveryAxisToTheSafeStateOnTheSameTick) {
  MultiAxisBridge bridge = two_axes();
  // x has commands for 100 ticks, y for the first 10 only: y's watchdog (2 ms = 20 ticks after its
  // last command, tick 9) is due at tick 30, and x, whose buffer is full, must go with it.
  for (std::int64_t k = 0; k < 100; ++k) {
    ASSERT_TRUE(bridge.submit(0, {k, 10.0, 0.0, 1, 2}));
    if (k < 10) {
      ASSERT_TRUE(bridge.submit(1, {k, -10.0, 0.0, 1, 2}));
    }
  }
  bridge.arm(0);
  const std::array<double, 2> y{};
  std::array<BridgeTick, 2> out{};
  std::int64_t first_safe = -1;
  for (std::int64_t k = 0; k < 60; ++k) {
    bridge.tick(k, y, out);
    const bool x_safe = (out[0].flags & sample_flags::kSafeState) != 0;
    const bool y_safe = (out[1].flags & sample_flags::kSafeState) != 0;
    ASSERT_EQ(x_safe, y_safe) << "tick " << k;
    if (x_safe && first_safe < 0) first_safe = k;
  }
  EXPECT_EQ(first_safe, 30);
  EXPECT_FALSE(bridge.armed());
  EXPECT_EQ(bridge.stage_trips(), 1u);
  EXPECT_EQ(bridge.tripped_by(), 1);
  // Both ramp to their safe voltage (0 V) at the safe ramp's rate (1e3 V/s: 0.1 V per tick).
  EXPECT_NEAR(bridge.axis(0).last_applied_V(), 10.0 - 30 * 0.1, 1e-9);
  EXPECT_NEAR(bridge.axis(1).last_applied_V(), -10.0 + 30 * 0.1, 1e-9);
  // Armed again together.
  bridge.arm(60);
  EXPECT_TRUE(bridge.axis(0).armed() && bridge.axis(1).armed());
}

TEST(MultiAxisBridge, DisarmingTakesEveryAxis) {
  MultiAxisBridge bridge = two_axes();
  bridge.arm(0);
  bridge.disarm();
  EXPECT_FALSE(bridge.axis(0).armed() || bridge.axis(1).armed());
}

TEST(MultiAxisBridge, RefusesAxisCountsThatDoNotMatchAndNamesTheAxisOfABadLimit) {
  const std::array<ActuatorLimits, 3> limits{};
  const std::array<FeedbackGains, 3> servo{};
  EXPECT_EQ(refused_field([&] { MultiAxisBridge(2, limits, servo); }), "axes");
  EXPECT_EQ(refused_field([&] { MultiAxisBridge(4, limits, servo); }), "axes");
  EXPECT_EQ(refused_field([&] { MultiAxisBridge(0, std::span(limits).first(0), std::span(servo).first(0)); }), "axes");
  ActuatorLimits bad;
  bad.slew_V_per_s = -1.0;
  EXPECT_EQ(refused_field([&] { two_axes(bad); }), "actuator.y.slew_V_per_s");
}

TEST(MultiAxisBridge, ACommandForAnAxisTheStageDoesNotHaveIsRefused) {
  MultiAxisBridge bridge = two_axes();
  EXPECT_FALSE(bridge.submit(2, {0, 1.0, 0.0, 1, 2}));
  EXPECT_FALSE(bridge.submit(-1, {0, 1.0, 0.0, 1, 2}));
  EXPECT_EQ(bridge.misaddressed(), 2u);
}

}  // namespace
}  // namespace hystloop
