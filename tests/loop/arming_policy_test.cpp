// The bridge's arming rules (common/loop/arming_policy.hpp) with time as the tick argument: what
// BridgeRealtime's thread does at every tick, without the thread.
#include "loop/arming_policy.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "loop/bridge_test_rig.hpp"

namespace hystloop {
namespace {

using testing::command;
using testing::kDt;

// A BridgeCore (disarmed, watchdog 2 ms = 20 ticks) and the policy, ticked like BridgeRealtime.
struct ArmingRig {
  explicit ArmingRig(ArmingSettings settings)
      : core(std::make_unique<BridgeCore>(ActuatorLimits{}, FeedbackGains{}, kDt)), policy(settings) {}

  // One tick: the operator's request, commands for [k, k + supply) submitted, then the policy
  // and the core as BridgeRealtime::tick orders them.
  void tick(ArmRequest request = ArmRequest::kNone, std::int64_t supply = 0) {
    policy.request(request, k, *core);
    for (std::int64_t j = next_supplied; j < k + supply; ++j) core->submit(command(j, 1.0));
    if (k + supply > next_supplied) next_supplied = k + supply;
    seen = seen || supply > 0;
    policy.before_tick(k, seen, *core);
    core->tick(k, 0.0);
    policy.after_tick(k, *core);
    ++k;
  }
  void run(std::int64_t n, std::int64_t supply) {
    for (std::int64_t i = 0; i < n; ++i) tick(ArmRequest::kNone, supply);
  }

  std::unique_ptr<BridgeCore> core;
  ArmingPolicy policy;
  std::int64_t k = 0;
  std::int64_t next_supplied = 0;
  bool seen = false;
};

ArmingSettings settings(bool auto_arm, double rearm_s) { return {auto_arm, rearm_s, kDt}; }

TEST(ArmingPolicy, WithoutAutoArmOnlyAnOperatorArms) {
  ArmingRig rig(settings(false, 0.0));
  rig.run(50, 10);
  EXPECT_FALSE(rig.core->armed());
  rig.tick(ArmRequest::kArm, 10);
  EXPECT_TRUE(rig.core->armed());
  EXPECT_EQ(rig.policy.auto_arms(), 0u);
}

TEST(ArmingPolicy, AutoArmArmsOnceWhenCommandsFirstFlow) {
  ArmingRig rig(settings(true, 0.0));
  rig.run(5, 0);  // nothing buffered: no arm
  EXPECT_FALSE(rig.core->armed());
  rig.tick(ArmRequest::kNone, 10);
  EXPECT_TRUE(rig.core->armed());
  EXPECT_EQ(rig.policy.auto_arms(), 1u);
  rig.tick(ArmRequest::kDisarm, 10);  // an operator's disarm is never undone automatically
  rig.run(100, 10);
  EXPECT_FALSE(rig.core->armed());
  EXPECT_EQ(rig.policy.auto_arms(), 1u);
}

TEST(ArmingPolicy, ADisarmBeforeTheFirstCommandEndsTheAutoArm) {
  ArmingRig rig(settings(true, 0.0));
  rig.tick(ArmRequest::kDisarm, 0);
  rig.run(20, 10);
  EXPECT_FALSE(rig.core->armed());
}

TEST(ArmingPolicy, TheStopDisarmsForGood) {
  ArmingRig rig(settings(true, 0.0));
  rig.run(5, 10);
  ASSERT_TRUE(rig.core->armed());
  rig.policy.stop(*rig.core);
  EXPECT_TRUE(rig.policy.stopping());
  EXPECT_FALSE(rig.core->armed());
  rig.tick(ArmRequest::kArm, 10);  // a late ARM is refused
  rig.run(10, 10);
  EXPECT_FALSE(rig.core->armed());
}

// The watchdog trips 20 dry ticks after the last supplied one; without re-arm it stays safe.
TEST(ArmingPolicy, ATripIsNoticedAtItsTickAndNotUndoneByDefault) {
  ArmingRig rig(settings(true, 0.0));
  rig.run(10, 1);  // supplied just in time through tick 9
  ASSERT_TRUE(rig.core->armed());
  rig.run(40, 0);
  EXPECT_FALSE(rig.core->armed());
  EXPECT_TRUE(rig.policy.tripped());
  const std::int64_t trip = rig.policy.last_trip_tick();
  EXPECT_GT(trip, 9 + 10);  // not at the first dry tick ...
  EXPECT_LE(trip, 9 + 21);  // ... and within the watchdog's 20 ticks (+ the one that trips)
  rig.run(2000, 10);        // commands again: no automatic re-arm when rearm_after_trip_s = 0
  EXPECT_FALSE(rig.core->armed());
  rig.tick(ArmRequest::kArm, 10);
  EXPECT_TRUE(rig.core->armed());
  EXPECT_FALSE(rig.policy.tripped());
}

TEST(ArmingPolicy, OptInReArmWaitsItsDelayAfterTheTrip) {
  ArmingRig rig(settings(true, 0.01));  // 100 ticks
  rig.run(10, 1);
  rig.run(40, 0);
  ASSERT_TRUE(rig.policy.tripped());
  const std::int64_t trip = rig.policy.last_trip_tick();
  while (rig.k < trip + 99) rig.tick(ArmRequest::kNone, 10);
  EXPECT_FALSE(rig.core->armed()) << "re-armed before rearm_after_trip_s had passed";
  rig.run(2, 10);
  EXPECT_TRUE(rig.core->armed());
  EXPECT_EQ(rig.policy.auto_arms(), 2u);
  EXPECT_FALSE(rig.policy.tripped());
}

TEST(ArmingPolicy, AnOperatorsDisarmAfterATripIsNotUndoneByTheReArm) {
  ArmingRig rig(settings(true, 0.01));
  rig.run(10, 1);
  rig.run(40, 0);
  ASSERT_TRUE(rig.policy.tripped());
  rig.tick(ArmRequest::kDisarm, 10);
  rig.run(500, 10);
  EXPECT_FALSE(rig.core->armed());
}

}  // namespace
}  // namespace hystloop
