// BridgeCore's safety rules (docs/TIMING.md), with time as an argument: which
// command reaches the actuator at tick k, range and slew clamp, rejections, late ticks, the
// watchdog and the ramp to the safe voltage. The servo has its own file: bridge_servo_test.cpp.
#include "loop/bridge_core.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <vector>

#include "bridge_test_rig.hpp"
#include "core/errors.hpp"
#include "loop/compensator.hpp"
#include "loop/simulated_stage.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using namespace testing;  // the rig (bridge_test_rig.hpp): BridgeRig, command, kDt, kNaN, ...

bool has(const BridgeTick& t, std::int32_t flag) { return (t.flags & flag) != 0; }

std::unique_ptr<BridgeCore> make_bridge(const ActuatorLimits& limits = {}, const FeedbackGains& gains = {}) {
  return std::make_unique<BridgeCore>(limits, gains, kDt);
}

TEST(BridgeCore, StartsSafeAndBuffersCommandsOnlyForArmedTicks) {
  auto b = make_bridge();
  EXPECT_FALSE(b->armed());
  EXPECT_TRUE(b->submit(command(0, 3.0)));  // buffered; not applied while disarmed
  const BridgeTick t = b->tick(0, 0.0);
  EXPECT_EQ(t.u_applied_V, 0.0);
  EXPECT_TRUE(has(t, sample_flags::kSafeState));
  EXPECT_EQ(b->counters().applied, 0u);
  EXPECT_EQ(b->counters().safe_ticks, 1u);
  b->arm(1);
  ASSERT_TRUE(b->submit(command(1, 1.0, kNaN, 7)));
  ASSERT_TRUE(b->submit(command(2, 2.0, kNaN, 7)));
  EXPECT_EQ(b->buffer_depth(), 2);
  const BridgeTick t1 = b->tick(1, 0.0);
  EXPECT_EQ(t1.u_applied_V, 1.0);
  EXPECT_EQ(t1.u_ff_V, 1.0);
  EXPECT_EQ(t1.params_version, 7);
  EXPECT_EQ(t1.buffer_depth, 1);
  EXPECT_EQ(t1.flags, 0);
  EXPECT_EQ(b->tick(2, 0.0).u_applied_V, 2.0);
  EXPECT_EQ(b->counters().applied, 2u);
}

TEST(BridgeCore, ClampsToRangeAndSlew) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e4;  // 1 V per tick
  lim.watchdog_s = 1.0;
  BridgeRig rig(lim);
  // Far beyond the range: the slew limit takes it up 1 V per tick, the range stops it at u_max.
  for (int i = 1; i <= 260; ++i) {
    const BridgeTick t = rig.step(1000.0, kNaN);
    EXPECT_TRUE(has(t, sample_flags::kSaturated));
    EXPECT_DOUBLE_EQ(t.u_applied_V, std::min(static_cast<double>(i), lim.u_max_V)) << i;
    EXPECT_EQ(has(t, sample_flags::kSlewLimited), i < 250) << i;
  }
  // And down to u_min the same way.
  double prev = lim.u_max_V;
  for (int i = 0; i < 600; ++i) {
    const BridgeTick t = rig.step(-1e6, kNaN);
    ASSERT_NEAR(prev - t.u_applied_V, std::min(1.0, prev - lim.u_min_V), 1e-9) << i;
    prev = t.u_applied_V;
  }
  EXPECT_EQ(prev, lim.u_min_V);
  // Inside the range and the slew: applied as is, no flag.
  const BridgeTick t = rig.step(-249.5, kNaN);
  EXPECT_EQ(t.u_applied_V, -249.5);
  EXPECT_EQ(t.flags, 0);
  EXPECT_EQ(rig.bridge->counters().clamped, 860u);
  EXPECT_EQ(rig.bridge->counters().slew_limited, 249u + 499u);  // the last step of each run fits
}

TEST(BridgeCore, RejectsNonFiniteCommandsButAcceptsANaNReference) {
  auto b = make_bridge();
  b->arm(0);
  EXPECT_FALSE(b->submit(command(0, kNaN)));
  EXPECT_FALSE(b->submit(command(0, kInf)));
  EXPECT_FALSE(b->submit(command(0, -kInf)));
  EXPECT_FALSE(b->submit(command(0, 1.0, kInf)));
  EXPECT_FALSE(b->submit(command(0, 1.0, -kInf)));
  EXPECT_EQ(b->counters().rejected_nonfinite, 5u);
  EXPECT_EQ(b->buffer_depth(), 0);                // none of them took the tick's slot
  EXPECT_TRUE(b->submit(command(0, 1.0, kNaN)));  // NaN reference = none: the servo adds nothing
  const BridgeTick t = b->tick(0, 0.0);
  EXPECT_EQ(t.u_applied_V, 1.0);
  EXPECT_TRUE(std::isnan(t.y_ref_m));
  EXPECT_EQ(b->counters().rejected_nonfinite, 5u);
}

TEST(BridgeCore, RefusesStaleDuplicateAndFarFutureCommandsAndCountsThem) {
  auto b = make_bridge();
  b->arm(0);
  ASSERT_TRUE(b->submit(command(20, 1.0)));
  EXPECT_FALSE(b->submit(command(20, 2.0)));  // the first command for a tick stays
  EXPECT_EQ(b->counters().duplicates, 1u);
  for (std::int64_t k = 0; k <= 10; ++k) b->tick(k, 0.0);
  EXPECT_FALSE(b->submit(command(10, 4.0)));  // its tick has passed
  EXPECT_FALSE(b->submit(command(3, 4.0)));
  EXPECT_EQ(b->counters().stale, 2u);
  EXPECT_FALSE(b->submit(command(11 + CommandBuffer::kCapacityTicks, 4.0)));
  EXPECT_EQ(b->counters().rejected_future, 1u);
  for (std::int64_t k = 11; k < 20; ++k) b->tick(k, 0.0);
  EXPECT_EQ(b->tick(20, 0.0).u_applied_V, 1.0);
}

// A forged sensor stream 5000 ticks ahead makes the compensator plan for the forged future; the
// bridge refuses those commands itself, from its own clock, and keeps the real ones.
TEST(BridgeCore, CommandsFurtherAheadOfItsClockThanTheMaxLeadAreRefused) {
  auto b = make_bridge();
  b->set_max_lead_ticks(600);
  b->arm(0);
  for (std::int64_t k = 0; k < 100; ++k) b->tick(k, 0.0);  // next tick: 100
  EXPECT_TRUE(b->submit(command(700, 1.0)));               // exactly the lead
  EXPECT_FALSE(b->submit(command(701, 1.0)));
  EXPECT_FALSE(b->submit(command(5100, 200.0)));
  EXPECT_EQ(b->counters().rejected_future, 2u);
  EXPECT_TRUE(b->submit(command(100, 1.0)));
  EXPECT_THROW(b->set_max_lead_ticks(0), ParameterError);
  EXPECT_THROW(b->set_max_lead_ticks(CommandBuffer::kCapacityTicks + 1), ParameterError);
  EXPECT_EQ(b->max_lead_ticks(), 600);
}

// A late tick holds the last feedforward and reference, and the servo keeps acting on it.
TEST(BridgeCore, LateTicksHoldTheLastCommandAndKeepTheServoRunning) {
  ActuatorLimits lim;
  lim.watchdog_s = 1.0;
  auto b = make_bridge(lim, testing::servo_gains(0.0, 100.0));
  b->arm(0);
  const double ref = 1e-6;
  const double y = ref - 1e-9;  // a constant 1 nm error
  for (std::int64_t k = 0; k < 100; ++k) {
    b->submit(command(k, 10.0, ref, 4));
    b->tick(k, y);
  }
  // Each tick the integrator adds ki * e * dt / gain.
  const double per_tick = 100.0 * 1e-9 * kDt / testing::kGain;
  double u_fb = b->tick(100, y).u_fb_V;  // no command from here on
  for (std::int64_t k = 101; k < 150; ++k) {
    const BridgeTick t = b->tick(k, y);
    EXPECT_TRUE(has(t, sample_flags::kLateCommand));
    EXPECT_FALSE(has(t, sample_flags::kSafeState));
    EXPECT_EQ(t.u_ff_V, 10.0);
    EXPECT_EQ(t.y_ref_m, ref);
    EXPECT_EQ(t.params_version, 4);
    EXPECT_NEAR(t.u_fb_V - u_fb, per_tick, 1e-9 * per_tick);
    EXPECT_NEAR(t.u_applied_V, 10.0 + t.u_fb_V, 1e-12);
    u_fb = t.u_fb_V;
  }
  EXPECT_EQ(b->counters().late, 50u);
  EXPECT_EQ(b->counters().applied, 100u);
  // A command that arrives in time again is applied.
  b->submit(command(150, 20.0, ref));
  const BridgeTick t = b->tick(150, y);
  EXPECT_FALSE(has(t, sample_flags::kLateCommand));
  EXPECT_EQ(t.u_ff_V, 20.0);
}

// Watchdog: dry for exactly watchdog_s is not dry for MORE than watchdog_s.
TEST(BridgeCore, WatchdogToleratesADrySpellUpToWatchdogS) {
  ActuatorLimits lim;  // 2 ms = 20 ticks
  auto b = make_bridge(lim);
  b->arm(0);
  const auto supply = [&](std::int64_t from, std::int64_t to) {
    for (std::int64_t k = from; k < to; ++k) {
      b->submit(command(k, 5.0));
      ASSERT_FALSE(has(b->tick(k, 0.0), sample_flags::kSafeState)) << k;
    }
  };
  supply(0, 10);
  for (std::int64_t k = 10; k < 30; ++k) {  // 20 ticks dry: 2.0 ms
    const BridgeTick t = b->tick(k, 0.0);
    EXPECT_FALSE(has(t, sample_flags::kSafeState)) << k;
    EXPECT_EQ(t.u_applied_V, 5.0);
  }
  supply(30, 50);
  for (std::int64_t k = 50; k < 70; ++k) EXPECT_FALSE(has(b->tick(k, 0.0), sample_flags::kSafeState)) << k;
  // Tick 70 is the 21st without a command since tick 49: 2.1 ms.
  EXPECT_TRUE(has(b->tick(70, 0.0), sample_flags::kSafeState));
  EXPECT_EQ(b->counters().watchdog_trips, 1u);
  EXPECT_FALSE(b->armed());
}

// The same rule for any watchdog_s that is a whole number of ticks, as a settings file gives it
// ("0.0003"): the trip is at the (n + 1)-th dry tick, never the n-th.
TEST(BridgeCore, WatchdogTripsAtTheFirstTickBeyondWatchdogS) {
  std::ostringstream early;  // n -> tick of the trip, for every n that trips elsewhere
  for (int n = 1; n <= 60; ++n) {
    ActuatorLimits lim;
    lim.watchdog_s = static_cast<double>(n) / 1e4;
    auto b = make_bridge(lim);
    b->arm(0);
    b->submit(command(0, 5.0));
    b->tick(0, 0.0);
    std::int64_t tripped_at = -1;
    for (std::int64_t k = 1; k < n + 10 && tripped_at < 0; ++k) {
      if (has(b->tick(k, 0.0), sample_flags::kSafeState)) tripped_at = k;
    }
    if (tripped_at != n + 1) early << ' ' << n << "->" << tripped_at;
  }
  EXPECT_EQ(early.str(), "") << "watchdog_s = n ticks -> tick of the trip (want n + 1)";
}

TEST(BridgeCore, WatchdogRampsToTheSafeVoltageAndStaysUntilRearmed) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e7;
  lim.safe_u_V = 20.0;
  auto b = make_bridge(lim);
  b->arm(0);
  b->submit(command(0, 120.0));
  EXPECT_EQ(b->tick(0, 0.0).u_applied_V, 120.0);
  const double ramp_step = lim.safe_ramp_V_per_s * kDt;  // 0.1 V per tick
  std::int64_t k = 1;
  for (; k <= 20; ++k) EXPECT_EQ(b->tick(k, 0.0).u_applied_V, 120.0);  // late, held
  double prev = 120.0;
  std::int64_t reached = -1;
  for (; k < 2000; ++k) {
    if (k > 21) b->submit(command(k, 200.0));  // once tripped, fresh commands do not leave the safe state
    const BridgeTick t = b->tick(k, 0.0);
    ASSERT_TRUE(has(t, sample_flags::kSafeState)) << k;
    ASSERT_FALSE(has(t, sample_flags::kSlewLimited)) << k;  // the ramp is not a slew-limited command
    EXPECT_EQ(t.u_ff_V, 0.0);
    EXPECT_EQ(t.u_fb_V, 0.0);
    EXPECT_TRUE(std::isnan(t.y_ref_m));
    ASSERT_LE(t.u_applied_V, prev);  // monotone
    ASSERT_LE(prev - t.u_applied_V, ramp_step * (1 + 1e-12)) << k;
    if (reached < 0 && t.u_applied_V == lim.safe_u_V) reached = k;
    prev = t.u_applied_V;
  }
  // 100 V at 1000 V/s: 1000 ticks from the trip at tick 21.
  EXPECT_GE(reached, 21 + 999);
  EXPECT_LE(reached, 21 + 1000);
  EXPECT_EQ(prev, lim.safe_u_V);
  EXPECT_EQ(b->counters().watchdog_trips, 1u);
  // A re-arm does: from the voltage it is at, under the slew limit.
  b->arm(k);
  b->submit(command(k, 50.0));
  const BridgeTick t = b->tick(k, 0.0);
  EXPECT_FALSE(has(t, sample_flags::kSafeState));
  EXPECT_EQ(t.u_applied_V, 50.0);
}

TEST(BridgeCore, DisarmRampsToTheSafeVoltage) {
  BridgeRig rig;
  for (int i = 0; i < 100; ++i) rig.step(100.0, kNaN);
  ASSERT_EQ(rig.bridge->last_applied_V(), 100.0);
  rig.bridge->disarm();
  const BridgeTick t = rig.step(100.0, kNaN);
  EXPECT_TRUE(has(t, sample_flags::kSafeState));
  EXPECT_NEAR(t.u_applied_V, 100.0 - 0.1, 1e-12);
  EXPECT_EQ(rig.bridge->counters().watchdog_trips, 0u);
}

// The slew limit protects the actuator whatever moves it: the ramp to safety must not exceed it.
// Either a faster ramp is refused by the settings or the ramp is held to the slew limit.
TEST(BridgeCore, TheSafeRampNeverExceedsTheSlewLimit) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e3;
  lim.safe_ramp_V_per_s = 1e4;
  lim.watchdog_s = 1.0;
  try {
    BridgeRig rig(lim);
    for (int i = 0; i < 2000; ++i) rig.step(100.0, kNaN);
    ASSERT_EQ(rig.bridge->last_applied_V(), 100.0);
    rig.bridge->disarm();
    double prev = 100.0;
    for (int i = 0; i < 2000; ++i) {
      const double u = rig.step(100.0, kNaN).u_applied_V;
      ASSERT_LE(std::abs(u - prev), lim.slew_V_per_s * kDt * (1 + 1e-12)) << "ramp tick " << i;
      prev = u;
    }
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "actuator.safe_ramp_V_per_s");
  }
}

// A dead compensator (docs/TIMING.md): the bridge follows the plan it was sent, then ramps to
// safety at most watchdog_s after the last planned tick, and never leaves the range or the slew.
TEST(BridgeCore, ADeadCompensatorStopsTheStageWithinHorizonPlusWatchdog) {
  const ActuatorLimits lim;
  FeedbackGains servo;
  servo.kp = 0.1;
  servo.ki = 600.0;
  auto bridge_ptr = make_bridge(lim, servo);
  BridgeCore& bridge = *bridge_ptr;
  CompensatorConfig cc;
  cc.mode = FeedforwardMode::kMem;
  cc.horizon_ticks = 300;
  Compensator comp(cc);
  TrajectorySpec reference = mem_paper_reference(0.05, 0.05);
  reference.shape_if_infeasible = true;  // the default MEM set needs a little more than +-250 V for it
  comp.set_trajectory(reference, 0.05);
  SimulatedStage stage(SimulatedStageConfig{});
  std::vector<CommandTick> plan(64);
  constexpr std::int64_t kDies = 4500;  // at 0.45 s, near the reference's peak (~250 V)
  const auto watchdog_ticks = static_cast<std::int64_t>(std::llround(lim.watchdog_s / kDt));

  bridge.arm(0);
  double y = 0.0;
  double prev_u = lim.safe_u_V;
  std::int64_t last_planned = -1;
  std::int64_t first_safe = -1;
  double u_at_trip = 0.0;
  std::int64_t safe_reached = -1;
  for (std::int64_t k = 0; k < kDies + cc.horizon_ticks + 4000; ++k) {
    const BridgeTick t = bridge.tick(k, y);
    y = stage.step(t.u_applied_V, static_cast<double>(k) * kDt, kDt);
    ASSERT_GE(t.u_applied_V, lim.u_min_V) << k;
    ASSERT_LE(t.u_applied_V, lim.u_max_V) << k;
    ASSERT_LE(std::abs(t.u_applied_V - prev_u), lim.slew_V_per_s * kDt * (1 + 1e-12)) << k;
    prev_u = t.u_applied_V;
    if (k < kDies) {
      comp.observe({k, t.u_applied_V, y});
      if ((k + 1) % 10 == 0) {
        while (const std::size_t n = comp.plan(plan)) {
          for (std::size_t i = 0; i < n; ++i) ASSERT_TRUE(bridge.submit(plan[i])) << plan[i].seq;
          last_planned = plan[n - 1].seq;
        }
      }
    }
    if (k >= 10 && k <= last_planned) {  // ticks 0-9 precede the first block's answer
      ASSERT_FALSE(has(t, sample_flags::kLateCommand)) << k;
      ASSERT_FALSE(has(t, sample_flags::kSafeState)) << k;
    }
    if (first_safe < 0 && has(t, sample_flags::kSafeState)) {
      first_safe = k;
      u_at_trip = t.u_applied_V;
    }
    if (first_safe >= 0 && safe_reached < 0 && t.u_applied_V == lim.safe_u_V) safe_reached = k;
  }
  ASSERT_GE(last_planned, kDies - 1 + cc.horizon_ticks - 10);
  ASSERT_GE(first_safe, 0) << "never reached the safe state";
  EXPECT_LE(first_safe, last_planned + watchdog_ticks + 1);
  EXPECT_GT(first_safe, last_planned + watchdog_ticks);  // not before the buffer is dry for watchdog_s
  EXPECT_GT(std::abs(u_at_trip), 100.0);                 // the test stops a stage that was really moving
  ASSERT_GE(safe_reached, 0);
  EXPECT_LE(
      safe_reached - first_safe,
      static_cast<std::int64_t>(std::ceil(std::abs(u_at_trip - lim.safe_u_V) / (lim.safe_ramp_V_per_s * kDt))) + 1);
  EXPECT_EQ(bridge.counters().watchdog_trips, 1u);
  EXPECT_EQ(bridge.counters().stale, 0u);  // the first block plans from the tick after its samples
  EXPECT_EQ(bridge.counters().late, 10u + static_cast<std::uint64_t>(watchdog_ticks));  // before it, and the dry spell
}

// Property: whatever arrives (random, hostile, missing, duplicated), whatever the sensor says,
// the applied voltage stays in range and within the slew limit of the previous one, and the
// per-tick path allocates nothing.
TEST(BridgeCore, NeverAppliesOutsideRangeOrSlew) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> wild(-1e4, 1e4);
  std::uniform_real_distribution<double> position(-5e-6, 5e-6);
  std::uniform_int_distribution<int> what(0, 99);
  ActuatorLimits lim;
  auto b = make_bridge(lim, testing::servo_gains(0.5, 2000.0));
  double prev = lim.safe_u_V;
  const double nan_or_inf[] = {kNaN, kInf, -kInf};
  testing::AllocationCounter allocations;
  for (std::int64_t k = 0; k < 200000; ++k) {
    const int w = what(rng);
    if (w == 0) b->arm(k);
    if (w == 1 && k % 7 == 0) b->disarm();
    const bool silent = k % 20000 >= 19900;  // now and then nothing arrives: the watchdog trips
    for (int i = 0; i < (silent ? 0 : w % 4); ++i) {
      const double u = w > 95 ? nan_or_inf[w % 3] : wild(rng);
      const double ref = w % 5 == 0 ? kNaN : position(rng);
      b->submit(command(k + (w % 9) - 2, u, ref));
    }
    const double y = w == 50 ? kNaN : position(rng);
    const BridgeTick t = b->tick(k, y);
    ASSERT_GE(t.u_applied_V, lim.u_min_V) << k;
    ASSERT_LE(t.u_applied_V, lim.u_max_V) << k;
    ASSERT_LE(std::abs(t.u_applied_V - prev), lim.slew_V_per_s * kDt * (1 + 1e-12)) << k;
    ASSERT_TRUE(std::isfinite(t.u_fb_V)) << k;
    prev = t.u_applied_V;
  }
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_GT(b->counters().applied, 1000u);
  EXPECT_GT(b->counters().late, 1000u);
  EXPECT_GT(b->counters().clamped, 1000u);
  EXPECT_GT(b->counters().watchdog_trips, 10u);
}

TEST(ActuatorLimits, RefusesBadValuesNamingTheField) {
  ActuatorLimits lim;
  lim.u_max_V = -300;
  EXPECT_EQ(testing::refused_field([&] { lim.validate(); }), "actuator.u_max_V");
  lim = {};
  lim.watchdog_s = 0;
  EXPECT_THROW(lim.validate(), ParameterError);
  lim = {};
  lim.safe_u_V = 300;
  EXPECT_THROW(BridgeCore(lim, FeedbackGains{}), ParameterError);
  try {
    BridgeCore core(ActuatorLimits{}, FeedbackGains{}, 0.0);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "bridge.dt_s");
  }
}

}  // namespace
}  // namespace hystloop
