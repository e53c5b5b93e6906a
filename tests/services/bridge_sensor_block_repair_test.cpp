// A sensor block the message contract refuses is published repaired, never dropped
// (bridge/sensor_block_repair.hpp): each refused value replaced by one the contract allows and the
// tick flagged, the last good values carried across blocks, a block that passes left as it is, no
// allocation; a period with such samples DEGRADED; and the probe's case, a servo gone wild (kp = 1e300) whose
// corrections no message may carry, ends up in a block that passes the Publisher's check with every tick in it.
#include "lcm/sensor_block_repair.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "lcm/blocks.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "loop/bridge_core.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int32_t kSaturated = sensor_block_t::SATURATED;
constexpr std::int32_t kSensorFault = sensor_block_t::SENSOR_FAULT;
constexpr std::int32_t kSimulated = sensor_block_t::SIMULATED;

SensorTick tick(std::int64_t seq, double u_V, double u_fb_V, double y_m, double y_ref_m = 1e-7,
                std::int32_t flags = kSimulated) {
  return SensorTick{1000 + seq * 100, seq, u_V, u_V - u_fb_V, u_fb_V, y_ref_m, y_m, flags};
}

sensor_block_t block_of(std::initializer_list<SensorTick> ticks) {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, ticks.begin()->seq, ticks.begin()->utime, 1e-4);
  for (const SensorTick& t : ticks) append_tick(b, t);
  return b;
}

TEST(BridgeSensorBlockRepair, ABlockThatPassesIsLeftAsItIs) {
  SensorBlockRepair repair;
  sensor_block_t b = block_of({tick(0, 10.0, 1.0, 1e-7), tick(1, 11.0, 1.0, 1.1e-7, kNaN)});
  const sensor_block_t before = b;
  ASSERT_EQ(check_message(b), Verdict::kOk);
  EXPECT_FALSE(repair.repair(b).any());
  EXPECT_EQ(b.u_fb_V, before.u_fb_V);
  EXPECT_EQ(b.flags, before.flags);
  EXPECT_TRUE(std::isnan(b.y_ref_m[1]));  // NaN: no reference, which the contract allows
}

TEST(BridgeSensorBlockRepair, EveryRefusedValueIsReplacedAndItsTickFlagged) {
  SensorBlockRepair repair;
  sensor_block_t good = block_of({tick(0, 10.0, 1.0, 2e-7)});
  repair.repair(good);  // the last good u and y: 10 V, 2e-7 m
  sensor_block_t b =
      block_of({tick(1, 250.0, 1e300, 2.1e-7),                       // a servo gone wild
                tick(2, kNaN, -kInf, kNaN),                          // nothing finite
                tick(3, 12.0, 0.5, 2.2e-7, kInf, kSimulated | 128),  // an infinite reference, an unknown bit
                tick(4, 13.0, 0.5, 5.0)});                           // y beyond 1 m: a units error
  b.buffer_depth_ticks = -1;
  ASSERT_NE(check_message(b), Verdict::kOk);
  const SensorRepair r = repair.repair(b);
  EXPECT_EQ(check_message(b), Verdict::kOk);
  EXPECT_EQ(b.n_ticks, 4);  // every tick stays in the record
  EXPECT_EQ(r.ticks, 4);
  EXPECT_EQ(r.voltages, 5);  // u_ff and u_fb of tick 1 (u_ff = u - u_fb = -1e300); u, u_ff (NaN), u_fb of tick 2
  EXPECT_EQ(r.positions, 2);
  EXPECT_EQ(r.references, 1);
  EXPECT_EQ(r.flag_words, 1);
  EXPECT_TRUE(r.buffer_depth);
  EXPECT_EQ(b.buffer_depth_ticks, 0);

  EXPECT_EQ(b.u_fb_V[0], kMaxAbsVoltage_V);
  EXPECT_EQ(b.u_V[0], 250.0);  // what was applied, within the contract, kept
  EXPECT_EQ(b.flags[0], kSimulated | kSaturated);
  EXPECT_EQ(b.u_V[1], 250.0);  // NaN applied: the last good one, the tick before
  EXPECT_EQ(b.u_fb_V[1], -kMaxAbsVoltage_V);
  EXPECT_EQ(b.y_m[1], 2.1e-7);  // the last good position
  EXPECT_EQ(b.flags[1], kSimulated | kSaturated | kSensorFault);
  EXPECT_TRUE(std::isnan(b.y_ref_m[2]));
  EXPECT_EQ(b.flags[2], kSimulated);  // the unknown bit cleared
  EXPECT_EQ(b.y_m[3], 2.2e-7);
  EXPECT_EQ(b.flags[3], kSimulated | kSensorFault);

  // The next block's first bad position takes the last good one of this block.
  sensor_block_t next = block_of({tick(5, 14.0, 0.5, kInf)});
  repair.repair(next);
  EXPECT_EQ(next.y_m[0], 2.2e-7);
}

TEST(BridgeSensorBlockRepair, ItAllocatesNothing) {
  SensorBlockRepair repair;
  sensor_block_t b = block_of({tick(0, 250.0, 1e300, kNaN), tick(1, 250.0, 1e300, 1e-7)});
  testing::AllocationCounter counter;
  const SensorRepair r = repair.repair(b);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(r.ticks, 2);
}

// The probe's case without LCM: a core whose servo has kp = 1e300 (past the bounds the config and
// SET_GAINS now enforce) produces corrections the Publisher's check refuses; repaired, the block
// passes with all its ticks, each flagged.
TEST(BridgeSensorBlockRepair, AServoGoneWildStillLeavesEveryTickInTheRecord) {
  FeedbackGains wild;
  wild.kp = 1e300;
  BridgeCore core(ActuatorLimits{}, wild, 1e-4);
  core.arm(0);
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, 0, 0, 1e-4);
  double y = 0.0;
  for (std::int64_t k = 0; k < 20; ++k) {
    core.submit({k, 10.0, 1e-7, 1, 2});
    const BridgeTick t = core.tick(k, y);
    y = 6.3e-9 * t.u_applied_V;  // a stage without dynamics
    append_tick(b, SensorTick{k * 100, k, t.u_applied_V, t.u_ff_V, t.u_fb_V, t.y_ref_m, y, t.flags});
  }
  ASSERT_NE(check_message(b), Verdict::kOk);  // what the Publisher refused: 2 ms gone from the record
  SensorBlockRepair repair;
  const SensorRepair r = repair.repair(b);
  EXPECT_EQ(check_message(b), Verdict::kOk);
  EXPECT_EQ(b.n_ticks, 20);
  EXPECT_GT(r.ticks, 0);
  for (std::int32_t i = 0; i < b.n_ticks; ++i) {
    if (std::abs(b.u_fb_V[static_cast<std::size_t>(i)]) == kMaxAbsVoltage_V) {
      EXPECT_NE(b.flags[static_cast<std::size_t>(i)] & kSaturated, 0) << i;
    }
  }
}

// With several axes each keeps its own last good values: a lost y reading of axis y is y's last
// good one, never x's; a tick counts once whichever axes were repaired.
TEST(SensorBlockRepair, EachAxisKeepsItsOwnLastGoodValues) {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, 0, 1000, 1e-4, 2);
  const std::array<SensorTick, 2> first{tick(0, 1.0, 0.0, 1e-6), tick(0, 2.0, 0.0, -3e-6)};
  const std::array<SensorTick, 2> lost{tick(1, kNaN, 0.0, 1.1e-6), tick(1, 2.5, 0.0, kNaN)};
  const std::array<SensorTick, 2> both{tick(2, kInf, 0.0, kNaN), tick(2, kNaN, 0.0, kInf)};
  ASSERT_TRUE(append_tick(b, first));
  ASSERT_TRUE(append_tick(b, lost));
  ASSERT_TRUE(append_tick(b, both));
  SensorBlockRepair repair;
  const SensorRepair r = repair.repair(b);
  EXPECT_EQ(check_message(b), Verdict::kOk);
  EXPECT_EQ(r.ticks, 2);                                  // ticks 1 and 2, each once
  EXPECT_EQ(sensor_tick(b, 1, 0).u_V, 1.0);               // x's last good u
  EXPECT_EQ(sensor_tick(b, 1, 1).y_m, -3e-6);             // y's last good y, not x's 1.1e-6
  EXPECT_EQ(sensor_tick(b, 2, 0).y_m, 1.1e-6);            // x's last good y
  EXPECT_EQ(sensor_tick(b, 2, 1).u_V, 2.5);               // y's last good u
  EXPECT_EQ(sensor_tick(b, 2, 1).y_m, -3e-6);             // again y's own
  EXPECT_EQ(sensor_tick(b, 2, 0).u_V, kMaxAbsVoltage_V);  // an infinite voltage clamped to the bound
  EXPECT_NE(sensor_tick(b, 1, 1).flags & kSensorFault, 0);
  EXPECT_EQ(sensor_tick(b, 1, 0).flags & kSensorFault, 0);
}

}  // namespace
}  // namespace hystloop
