#include "loop/bridge_core.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;

double t_of(std::int64_t k) { return static_cast<double>(k) * kDt; }

TEST(BridgeCore, StartsSafeAndIgnoresCommandsUntilArmed) {
  BridgeCore b(ActuatorLimits{});
  EXPECT_FALSE(b.submit(0, 10.0, 1, 0.0));
  const BridgeTick t = b.tick(0, 0.0);
  EXPECT_EQ(t.u_applied_V, 0.0);
  EXPECT_TRUE(t.flags & sample_flags::kSafeState);
  EXPECT_EQ(b.counters().ignored_disarmed, 1u);
}

TEST(BridgeCore, AppliesTheCommandMeantForTheTick) {
  BridgeCore b(ActuatorLimits{});
  b.arm(0.0);
  ASSERT_TRUE(b.submit(0, 1.0, 7, 0.0));
  ASSERT_TRUE(b.submit(1, 2.0, 7, 0.0));
  EXPECT_EQ(b.tick(0, t_of(0)).u_applied_V, 1.0);
  const BridgeTick t1 = b.tick(1, t_of(1));
  EXPECT_EQ(t1.u_applied_V, 2.0);
  EXPECT_EQ(t1.params_version, 7);
  EXPECT_EQ(b.counters().applied, 2u);
}

TEST(BridgeCore, HoldsTheLastCommandWhenLateAndCountsIt) {
  BridgeCore b(ActuatorLimits{});
  b.arm(0.0);
  b.submit(0, 3.0, 1, 0.0);
  b.tick(0, t_of(0));
  const BridgeTick t = b.tick(1, t_of(1));
  EXPECT_EQ(t.u_applied_V, 3.0);
  EXPECT_TRUE(t.flags & sample_flags::kLateCommand);
  EXPECT_EQ(b.counters().late, 1u);
  // A command for a tick that has passed is stale, not applied.
  EXPECT_FALSE(b.submit(1, 4.0, 1, t_of(1)));
  EXPECT_EQ(b.counters().stale, 1u);
}

TEST(BridgeCore, RejectsNonFiniteAndFarFutureCommands) {
  BridgeCore b(ActuatorLimits{});
  b.arm(0.0);
  EXPECT_FALSE(b.submit(0, std::numeric_limits<double>::quiet_NaN(), 1, 0.0));
  EXPECT_FALSE(b.submit(0, std::numeric_limits<double>::infinity(), 1, 0.0));
  EXPECT_FALSE(b.submit(BridgeCore::kBufferTicks, 1.0, 1, 0.0));
  EXPECT_EQ(b.counters().rejected_nonfinite, 2u);
  EXPECT_EQ(b.counters().rejected_future, 1u);
}

TEST(BridgeCore, ClampsToRangeAndSlew) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e4;  // 1 V per tick
  BridgeCore b(lim);
  b.arm(0.0);
  b.submit(0, 1000.0, 1, 0.0);
  const BridgeTick t = b.tick(0, 0.0);
  EXPECT_DOUBLE_EQ(t.u_applied_V, 1.0);
  EXPECT_TRUE(t.flags & sample_flags::kSaturated);
  EXPECT_TRUE(t.flags & sample_flags::kSlewLimited);
  EXPECT_EQ(b.counters().clamped, 1u);
}

TEST(BridgeCore, WatchdogRampsToSafeVoltageAndStaysUntilRearmed) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e7;
  BridgeCore b(lim);
  b.arm(0.0);
  b.submit(0, 100.0, 1, 0.0);
  EXPECT_EQ(b.tick(0, 0.0).u_applied_V, 100.0);
  // Silence: after watchdog_s the bridge trips and ramps at safe_ramp_V_per_s.
  std::int64_t k = 1;
  const auto trip_tick = static_cast<std::int64_t>(std::ceil(lim.watchdog_s / kDt)) + 1;
  double prev = 100.0;
  bool tripped = false;
  for (; k < 4000; ++k) {
    const BridgeTick t = b.tick(k, t_of(k));
    if (t.flags & sample_flags::kSafeState) {
      if (!tripped) {
        EXPECT_LE(k, trip_tick);
      }
      tripped = true;
      EXPECT_LE(std::abs(t.u_applied_V - prev), lim.safe_ramp_V_per_s * kDt + 1e-12);
    }
    prev = t.u_applied_V;
  }
  EXPECT_TRUE(tripped);
  EXPECT_EQ(prev, lim.safe_u_V);
  EXPECT_EQ(b.counters().watchdog_trips, 1u);
  // Fresh commands alone do not leave the safe state...
  b.submit(k, 50.0, 1, t_of(k));
  EXPECT_TRUE(b.tick(k, t_of(k)).flags & sample_flags::kSafeState);
  ++k;
  // ...a re-arm does.
  b.arm(t_of(k));
  b.submit(k, 50.0, 1, t_of(k));
  const BridgeTick t = b.tick(k, t_of(k));
  EXPECT_FALSE(t.flags & sample_flags::kSafeState);
  EXPECT_EQ(t.u_applied_V, 50.0);
}

// Property: whatever arrives (random, hostile, missing), the applied voltage stays in
// range and within the slew limit of the previous one.
TEST(BridgeCore, NeverAppliesOutsideRangeOrSlew) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> wild(-1e4, 1e4);
  std::uniform_int_distribution<int> what(0, 9);
  ActuatorLimits lim;
  BridgeCore b(lim);
  double prev = lim.safe_u_V;
  testing::AllocationCounter allocations;
  for (std::int64_t k = 0; k < 200000; ++k) {
    const int w = what(rng);
    if (w == 0) b.arm(t_of(k));
    if (w == 1 && k % 7 == 0) b.disarm();
    if (w >= 2) b.submit(k + (w % 3), w == 9 ? std::nan("") : wild(rng), 1, t_of(k));
    const BridgeTick t = b.tick(k, t_of(k));
    ASSERT_GE(t.u_applied_V, lim.u_min_V);
    ASSERT_LE(t.u_applied_V, lim.u_max_V);
    ASSERT_LE(std::abs(t.u_applied_V - prev), lim.slew_V_per_s * kDt * (1 + 1e-12));
    prev = t.u_applied_V;
  }
  EXPECT_EQ(allocations.allocations(), 0u);
}

TEST(ActuatorLimits, RefusesBadValuesNamingTheField) {
  ActuatorLimits lim;
  lim.u_max_V = -300;
  try {
    lim.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "actuator.u_max_V");
  }
  lim = {};
  lim.watchdog_s = 0;
  EXPECT_THROW(lim.validate(), ParameterError);
  lim = {};
  lim.safe_u_V = 300;
  EXPECT_THROW(BridgeCore{lim}, ParameterError);
}

}  // namespace
}  // namespace hystloop
