// The servo against the bridge's two clamps, range and slew: BridgeCore tells it each tick what
// they will let through, so at the slew limit its integrator follows the actuator instead of
// winding up, and no clamped tick ever has the integral grown toward the clamp; unclamped it is
// the plain PI of loop/feedback.hpp. And the clamped ticks counted, in total and per second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "bridge_test_rig.hpp"
#include "loop/bridge_core.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using namespace testing;  // the rig (bridge_test_rig.hpp): BridgeRig, command, kDt, kNaN, ...

constexpr std::int32_t kClampFlags = sample_flags::kSaturated | sample_flags::kSlewLimited;

ActuatorLimits slow_slew() {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e3;  // 0.1 V per tick: a 1 um step (~100 V) takes ~1000 ticks
  lim.watchdog_s = 1.0;
  return lim;
}

// True when the integral moved toward the clamp of a clamped tick: up when the command was cut
// down to what the bridge allowed, down when it was lifted.
bool grew_toward_the_clamp(const BridgeTick& t, double integral_before, double integral_after) {
  if ((t.flags & kClampFlags) == 0) return false;
  const double wanted = t.u_ff_V + t.u_fb_V;
  return wanted > t.u_applied_V ? integral_after > integral_before : integral_after < integral_before;
}

// A feedforward step of 100 V at a slew limit of 0.1 V per tick: every tick of the 0.1 s climb is
// clamped, and the stage lags it by up to 1 um. Before, the integrator took all of that error
// (~5e-8 m s: 1500 V of integral at ki 300) and the stage then overshot to the range's end; now
// the integral does not move while the clamp holds and the climb ends where the step asks.
TEST(BridgeClamp, AtTheSlewLimitTheIntegratorDoesNotWindUp) {
  BridgeRig rig(slow_slew(), servo_gains(0.1, 300.0));
  for (int i = 0; i < 3000; ++i) rig.step(0.0, 0.0);  // settled on the plant's 20 nm disturbance
  const double ref = 1e-6, u_ff = 100.0;              // the feedforward leaves 20 nm to the servo
  const double settled_integral = rig.bridge->servo().integral_m_s();
  std::size_t clamped = 0, grew = 0;
  double overshoot_m = 0.0, integral_at_top = 0.0;
  for (int i = 0; i < 6000; ++i) {
    const double before = rig.bridge->servo().integral_m_s();
    const BridgeTick t = rig.step(u_ff, ref);
    const double after = rig.bridge->servo().integral_m_s();
    if ((t.flags & kClampFlags) != 0) {
      ++clamped;
      integral_at_top = after;
    }
    if (grew_toward_the_clamp(t, before, after)) ++grew;
    overshoot_m = std::max(overshoot_m, rig.plant.y_m - ref);
  }
  EXPECT_GT(clamped, 900u) << "the climb must be slew-limited for the test to mean anything";
  EXPECT_EQ(grew, 0u) << "ticks clamped with the integral grown toward the clamp";
  EXPECT_NEAR(integral_at_top, settled_integral, 1e-12);  // 1e-12 m s = 0.03 V of integral
  EXPECT_LT(overshoot_m, 0.05 * ref);
  EXPECT_LT(std::abs(ref - rig.plant.y_m), 1e-12);  // and it arrives
}

// With kp = 0 the integral is the whole command: it must climb with the actuator at the slew
// limit, not freeze because one tick's growth (3 V) is more than the slew's step (0.1 V).
TEST(BridgeClamp, AnIntegralOnlyServoClimbsAtTheSlewLimit) {
  BridgeRig rig(slow_slew(), servo_gains(0.0, 300.0));
  std::vector<double> u;
  u.reserve(1500);
  for (int i = 0; i < 1500; ++i) u.push_back(rig.step(0.0, 1e-6).u_applied_V);
  // Climbing at the limit (the servo's first tick has no previous reference, the second acts).
  for (std::size_t i = 3; i < 900; ++i) ASSERT_NEAR(u[i] - u[i - 1], 0.1, 1e-6) << i;
  EXPECT_NEAR(rig.plant.y_m, 1e-6, 1e-8);
}

// Nothing clamped: the command is kp e + ki dt sum(e) over the gain, e the previous tick's
// reference minus the position measured at its end, on every tick.
TEST(BridgeClamp, UnclampedTheServoIsThePlainPi) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e7;
  lim.watchdog_s = 1.0;
  const double kp = 0.3, ki = 500.0;
  BridgeRig rig(lim, servo_gains(kp, ki));
  double prev_ref = kNaN, sum = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const double ref = 0.8e-6 * std::sin(2.0 * std::numbers::pi * 20.0 * i * kDt);
    const double y = rig.plant.y_m;
    const BridgeTick t = rig.step(10.0, ref);
    ASSERT_EQ(t.flags & kClampFlags, 0) << i;
    if (std::isnan(prev_ref)) {
      EXPECT_EQ(t.u_fb_V, 0.0);
    } else {
      const double e = prev_ref - y;
      sum += e * kDt;
      ASSERT_NEAR(t.u_fb_V, (kp * e + ki * sum) / kGain, 1e-9 * (1.0 + std::abs(t.u_fb_V))) << i;
    }
    prev_ref = ref;
  }
}

// Whatever arrives, with the notch on: the voltage stays in range and slew, a clamped tick never
// has the integral grown toward its clamp, and the per-tick path allocates nothing.
TEST(BridgeClamp, NoClampedTickGrowsTheIntegralTowardItsClamp) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> voltage(-300.0, 300.0);
  std::uniform_real_distribution<double> position(-3e-6, 3e-6);
  ActuatorLimits lim;
  lim.slew_V_per_s = 2e4;
  lim.watchdog_s = 1.0;
  FeedbackGains g = servo_gains(0.1, 2000.0);
  g.notch_hz = 1720.0;
  g.notch_q = 0.7;
  BridgeRig rig(lim, g);
  std::size_t clamped = 0, grew = 0;
  double prev_u = lim.safe_u_V, u_ff = 0.0, ref = 0.0;
  testing::AllocationCounter allocations;
  for (int i = 0; i < 200000; ++i) {
    if (i % 500 == 0) u_ff = voltage(rng), ref = position(rng);  // steps the clamps must stop
    const double before = rig.bridge->servo().integral_m_s();
    const BridgeTick t = rig.step(u_ff, ref);
    const double after = rig.bridge->servo().integral_m_s();
    if ((t.flags & kClampFlags) != 0) ++clamped;
    if (grew_toward_the_clamp(t, before, after)) ++grew;
    ASSERT_GE(t.u_applied_V, lim.u_min_V);
    ASSERT_LE(t.u_applied_V, lim.u_max_V);
    ASSERT_LE(std::abs(t.u_applied_V - prev_u), lim.slew_V_per_s * kDt * (1 + 1e-12));
    prev_u = t.u_applied_V;
  }
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_GT(clamped, 10000u);
  EXPECT_EQ(grew, 0u);
}

TEST(BridgeClamp, ATickClampedByBothLimitsCountsOnce) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e4;  // 1 V per tick
  lim.watchdog_s = 1.0;
  BridgeRig rig(lim);
  for (int i = 0; i < 300; ++i) rig.step(1000.0, kNaN);  // 250 ticks of both, then 50 of the range alone
  for (int i = 0; i < 100; ++i) rig.step(200.0, kNaN);   // 49 of the slew alone, then none
  const BridgeCounters& c = rig.bridge->counters();
  EXPECT_EQ(c.clamped, 300u);
  EXPECT_EQ(c.slew_limited, 249u + 49u);
  EXPECT_EQ(c.clamped_either, 300u + 49u);
}

TEST(BridgeClamp, ClampedLastSecondCountsTheLastWholeSecondOfLoopTime) {
  BridgeRig rig;  // 5 V per tick, 10 000 ticks per second
  const ClampCounts zero{};
  const auto equal = [](const ClampCounts& a, const ClampCounts& b) {
    return a.either == b.either && a.range == b.range && a.slew == b.slew;
  };
  // Second 0: 300 ticks asking for 1000 V (the first 49 also slew-limited on the way to 250 V),
  // then back to 0 V (49 slew-limited ticks down).
  for (int i = 0; i < 10000; ++i) {
    rig.step(i < 300 ? 1000.0 : 0.0, kNaN);
    ASSERT_TRUE(equal(rig.bridge->clamped_last_second(), zero)) << i;
  }
  const ClampCounts second0{300 + 49, 300, 49 + 49};
  for (int i = 0; i < 10000; ++i) {  // second 1: nothing clamped
    rig.step(0.0, kNaN);
    ASSERT_TRUE(equal(rig.bridge->clamped_last_second(), second0)) << i;
  }
  rig.step(0.0, kNaN);  // tick 20000: second 1 is the last whole one
  EXPECT_TRUE(equal(rig.bridge->clamped_last_second(), zero));
  rig.step(1000.0, kNaN);  // clamped in second 2, counted when it is over
  EXPECT_TRUE(equal(rig.bridge->clamped_last_second(), zero));
  rig.k = 26000;  // ticks not run (a hardware overrun) do not count
  rig.step(1000.0, kNaN);
  rig.k = 29999;
  rig.step(1000.0, kNaN);
  rig.step(1000.0, kNaN);  // tick 30000
  EXPECT_TRUE(equal(rig.bridge->clamped_last_second(), (ClampCounts{3, 3, 3})));
  rig.k = 50000;  // a gap of more than a second: the last whole one, 4, saw nothing
  rig.step(0.0, kNaN);
  EXPECT_TRUE(equal(rig.bridge->clamped_last_second(), zero));
}

}  // namespace
}  // namespace hystloop
