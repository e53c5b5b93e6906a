// The bridge's servo (docs/TIMING.md): PI on the previous tick's reference minus the measured
// position, added to the feedforward, with anti-windup at the actuator's range, a hold while safe,
// a reset when the command has no reference and bumpless gain changes. Driven on a first-order
// plant (bridge_test_rig.hpp) with a constant disturbance the feedforward does not know.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "bridge_test_rig.hpp"
#include "loop/bridge_core.hpp"

namespace hystloop {
namespace {

using namespace testing;  // the rig (bridge_test_rig.hpp): BridgeRig, command, kDt, kNaN, ...

constexpr double kRef = 1e-6;
constexpr double kFeedforward = 80.0;  // the plant needs (1 um - 20 nm) / gain = 98 V

ActuatorLimits patient_limits() {
  ActuatorLimits lim;
  lim.watchdog_s = 1.0;
  return lim;
}

// Ticks from the first of `errors` until |e| stays within tol (errors.size() if it never does).
std::size_t settle_ticks(const std::vector<double>& errors, double tol) {
  std::size_t n = errors.size();
  while (n > 0 && std::abs(errors[n - 1]) <= tol) --n;
  return n;
}

// Runs `ticks` ticks toward y_ref with feedforward u_ff; the tracking error after each tick.
std::vector<double> run(BridgeRig& rig, std::int64_t ticks, double u_ff, double y_ref) {
  std::vector<double> e;
  for (std::int64_t i = 0; i < ticks; ++i) {
    rig.step(u_ff, y_ref);
    e.push_back(y_ref - rig.plant.y_m);
  }
  return e;
}

TEST(BridgeServo, ActsOnThePreviousTicksReferenceAgainstTheMeasuredPosition) {
  ActuatorLimits lim = patient_limits();
  lim.slew_V_per_s = 1e7;
  auto b = std::make_unique<BridgeCore>(lim, servo_gains(1.0, 0.0), kDt);
  b->arm(0);
  b->submit(command(0, 0.0, 1e-6));
  b->submit(command(1, 0.0, 2e-6));
  EXPECT_EQ(b->tick(0, 0.0).u_fb_V, 0.0);  // no previous reference yet
  const BridgeTick t = b->tick(1, 0.25e-6);
  EXPECT_NEAR(t.u_fb_V, (1e-6 - 0.25e-6) / kGain, 1e-9);  // tick 0's reference, not tick 1's
  EXPECT_EQ(t.y_ref_m, 2e-6);
  EXPECT_NEAR(t.u_applied_V, t.u_fb_V, 1e-12);
}

TEST(BridgeServo, PiStepResponseConvergesWithoutSteadyError) {
  BridgeRig rig(patient_limits(), servo_gains(0.2, 300.0));
  run(rig, 100, 0.0, 0.0);
  const std::vector<double> e = run(rig, 3000, kFeedforward, kRef);
  EXPECT_LT(std::abs(e.back()), 1e-13);           // no steady error: the integrator took the rest
  EXPECT_LT(settle_ticks(e, 0.01 * kRef), 400u);  // within 1 % in 40 ms (crossover ~300 rad/s)
  const double overshoot = -*std::min_element(e.begin(), e.end());
  EXPECT_LT(overshoot, 0.2 * kRef);
  // Proportional alone leaves the error the feedforward and the disturbance left, divided by 1 + kp.
  BridgeRig p_only(patient_limits(), servo_gains(0.2, 0.0));
  const std::vector<double> ep = run(p_only, 3000, kFeedforward, kRef);
  EXPECT_NEAR(ep.back(), (kRef - 20e-9 - kGain * kFeedforward) / 1.2, 1e-12);
}

struct WindupRun {
  double worst_request_beyond_range_V = -1e300;  // u_ff + u_fb beyond [u_min, u_max] while holding
  std::size_t recovery_ticks = 0;                // to within 1 nm of the second reference
};

// Holds y_hold for 0.5 s (out of reach when the test wants saturation), then asks for y_after.
WindupRun hold_then_step(const ActuatorLimits& lim, double y_hold, double y_after) {
  BridgeRig rig(lim, servo_gains(0.2, 300.0));
  WindupRun out;
  for (int i = 0; i < 5000; ++i) {
    const BridgeTick t = rig.step(0.0, y_hold);
    const double request = t.u_ff_V + t.u_fb_V;
    const double beyond = std::max(request - lim.u_max_V, lim.u_min_V - request);
    out.worst_request_beyond_range_V = std::max(out.worst_request_beyond_range_V, beyond);
  }
  out.recovery_ticks = settle_ticks(run(rig, 5000, 0.0, y_after), 1e-9);
  return out;
}

// Saturated for 0.5 s, the integrator must not wind up: the servo's request stays at the range,
// and leaving saturation takes as long as the same step from an unsaturated start.
TEST(BridgeServo, AntiWindupAtTheActuatorRange) {
  const ActuatorLimits lim = patient_limits();  // +-250 V: the plant reaches 2.52 um
  const WindupRun saturated = hold_then_step(lim, 3.5e-6, 1e-6);
  const WindupRun unsaturated = hold_then_step(lim, 2.3e-6, 1e-6);  // 228 V: inside
  EXPECT_LT(saturated.worst_request_beyond_range_V, 5.0);
  EXPECT_LT(unsaturated.worst_request_beyond_range_V, 0.0);
  ASSERT_LT(unsaturated.recovery_ticks, 1000u);
  EXPECT_LE(saturated.recovery_ticks, unsaturated.recovery_ticks + 20) << "wound up while saturated";
  // The negative end alike.
  const WindupRun low = hold_then_step(lim, -3.5e-6, -1e-6);
  const WindupRun low_inside = hold_then_step(lim, -2.3e-6, -1e-6);
  EXPECT_LT(low.worst_request_beyond_range_V, 5.0);
  EXPECT_LE(low.recovery_ticks, low_inside.recovery_ticks + 20);
}

// A unipolar-ish range (piezo amplifiers often give -30..150 V): anti-windup must hold at the
// end that saturates, not at the larger magnitude of the two.
TEST(BridgeServo, AntiWindupAtAnAsymmetricRange) {
  ActuatorLimits lim = patient_limits();
  lim.u_min_V = -30.0;
  lim.u_max_V = 150.0;
  const WindupRun saturated = hold_then_step(lim, -1e-6, 0.5e-6);       // needs -102 V
  const WindupRun unsaturated = hold_then_step(lim, -0.27e-6, 0.5e-6);  // -29 V: just inside
  EXPECT_LT(saturated.worst_request_beyond_range_V, 5.0) << "the integrator wound up beyond u_min";
  EXPECT_LE(saturated.recovery_ticks, unsaturated.recovery_ticks + 20);
}

TEST(BridgeServo, GainChangeIsBumpless) {
  BridgeRig rig(patient_limits(), servo_gains(0.2, 300.0));
  run(rig, 3000, kFeedforward, kRef);
  const double before = rig.step(kFeedforward, kRef).u_fb_V;
  ASSERT_GT(before, 10.0);  // the servo carries the part the feedforward misses
  rig.bridge->set_servo_gains(servo_gains(0.6, 1200.0));
  EXPECT_EQ(rig.bridge->servo_gains().ki, 1200.0);
  EXPECT_EQ(rig.bridge->servo_gains().u_max_V, 250.0);  // from the actuator's range, not the caller
  EXPECT_EQ(rig.bridge->servo_gains().u_min_V, -250.0);
  const double after = rig.step(kFeedforward, kRef).u_fb_V;
  EXPECT_NEAR(after, before, 1e-6);
  // Invalid gains are ignored (the caller validates); the ones in force stay, still bumplessly.
  FeedbackGains bad = servo_gains(0.6, 1200.0);
  bad.ki = -1.0;
  rig.bridge->set_servo_gains(bad);
  EXPECT_EQ(rig.bridge->servo_gains().ki, 1200.0);
  EXPECT_NEAR(rig.step(kFeedforward, kRef).u_fb_V, before, 1e-6);
  // The new gains hold the loop: a disturbance step is rejected.
  rig.plant.disturbance_m = -30e-9;
  const std::vector<double> e = run(rig, 3000, kFeedforward, kRef);
  EXPECT_LT(std::abs(e.back()), 1e-13);
  EXPECT_LT(settle_ticks(e, 1e-10), 200u);  // faster than the old gains' ~300 rad/s allowed
}

// kp = 0 below makes the integrator's state visible: with no error, u_fb = ki * integral / gain.
// Runs on target until the integral holds the plant, then disarms: the feedback of the last armed
// tick.
double feedback_then_disarm(BridgeRig& rig) {
  run(rig, 5000, kFeedforward, kRef);
  const double held = rig.step(kFeedforward, kRef).u_fb_V;
  rig.bridge->disarm();
  return held;
}

TEST(BridgeServo, HeldWhileSafeAndResumedOnArm) {
  BridgeRig rig(patient_limits(), servo_gains(0.0, 300.0));
  const double held = feedback_then_disarm(rig);
  ASSERT_GT(held, 10.0);
  for (int i = 0; i < 500; ++i) {  // the plant sinks with the ramp: large errors, ignored
    const BridgeTick t = rig.step(kFeedforward, kRef);
    ASSERT_TRUE(t.flags & sample_flags::kSafeState);
    ASSERT_EQ(t.u_fb_V, 0.0);
  }
  BridgeCore& b = *rig.bridge;
  b.arm(rig.k);
  b.submit(command(rig.k, kFeedforward, kRef));
  b.submit(command(rig.k + 1, kFeedforward, kRef));
  EXPECT_EQ(b.tick(rig.k++, 0.5e-6).u_fb_V, 0.0);  // no previous reference on the first armed tick
  const BridgeTick t = b.tick(rig.k++, kRef);      // on target: the output is the integral alone
  EXPECT_FALSE(t.flags & sample_flags::kSafeState);
  EXPECT_NEAR(t.u_fb_V, held, 1e-9);
}

// The same when the first armed tick's command is late (re-armed before the compensator's
// commands are back): a late tick holds the servo, it does not mean "no reference".
TEST(BridgeServo, HeldWhileSafeAndResumedOnArmEvenIfTheFirstArmedTickIsLate) {
  BridgeRig rig(patient_limits(), servo_gains(0.0, 300.0));
  const double held = feedback_then_disarm(rig);
  ASSERT_GT(held, 10.0);
  for (int i = 0; i < 500; ++i) rig.step_without_command();
  BridgeCore& b = *rig.bridge;
  b.arm(rig.k);
  const BridgeTick late = b.tick(rig.k++, 0.5e-6);  // no command for the arm tick
  EXPECT_TRUE(late.flags & sample_flags::kLateCommand);
  EXPECT_EQ(late.u_fb_V, 0.0);
  b.submit(command(rig.k, kFeedforward, kRef));
  b.submit(command(rig.k + 1, kFeedforward, kRef));
  EXPECT_EQ(b.tick(rig.k++, 0.5e-6).u_fb_V, 0.0);  // no previous reference yet
  EXPECT_NEAR(b.tick(rig.k++, kRef).u_fb_V, held, 1e-9) << "the integrator was reset by a late tick";
}

TEST(BridgeServo, ResetWhenTheCommandHasNoReference) {
  BridgeRig rig(patient_limits(), servo_gains(0.0, 300.0));
  run(rig, 5000, kFeedforward, kRef);
  ASSERT_GT(rig.step(kFeedforward, kRef).u_fb_V, 10.0);
  const BridgeTick none = rig.step(kFeedforward, kNaN);  // e.g. an experiment's tick
  EXPECT_EQ(none.u_fb_V, 0.0);
  EXPECT_TRUE(std::isnan(none.y_ref_m));
  EXPECT_EQ(none.u_ff_V, kFeedforward);
  BridgeCore& b = *rig.bridge;
  b.submit(command(rig.k, kFeedforward, kRef));
  b.submit(command(rig.k + 1, kFeedforward, kRef));
  EXPECT_EQ(b.tick(rig.k++, 0.5e-6).u_fb_V, 0.0);  // the previous tick had no reference
  EXPECT_EQ(b.tick(rig.k++, kRef).u_fb_V, 0.0);    // on target, and nothing remembered
}

TEST(BridgeServo, ZeroGainsAddNothing) {
  BridgeRig rig(patient_limits(), FeedbackGains{});
  for (int i = 0; i < 100; ++i) {
    const BridgeTick t = rig.step(kFeedforward, kRef);
    ASSERT_EQ(t.u_fb_V, 0.0);
  }
}

}  // namespace
}  // namespace hystloop
