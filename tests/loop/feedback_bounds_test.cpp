// The servo's plausibility bounds (loop/feedback.hpp): each gain at its bound accepted and just
// beyond it refused naming the field, the value and the bound; the bounds follow the tick rate and
// the derivative filter; a run-time change beyond them (SET_GAINS kp = 1e300) leaves the gains in
// force, in the controller and in the bridge's core; and the bounds sit where their derivation
// says against Banning's stage (servo_loop_response.hpp).
#include "loop/feedback.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "loop/bridge_core.hpp"
#include "loop/servo_loop_response.hpp"

namespace hystloop {
namespace {

FeedbackGains gains(double kp, double ki, double kd) {
  FeedbackGains g;
  g.kp = kp;
  g.ki = ki;
  g.kd = kd;
  return g;
}

// The refusal's text, "" when accepted.
std::string refusal(const FeedbackGains& g) {
  try {
    g.check_bounds();
    return "";
  } catch (const ParameterError& e) {
    return e.what();
  }
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(FeedbackBounds, EachGainAtItsBoundIsAcceptedAndBeyondItRefusedNamingTheField) {
  const FeedbackGains defaults;  // 10 kHz, a 1 kHz derivative filter
  EXPECT_EQ(defaults.max_kp(), 2.0);
  EXPECT_DOUBLE_EQ(defaults.max_ki_per_s(), 1e4);
  const double kd_max = 2.0 * (1e-4 + 1.0 / (2.0 * std::numbers::pi * 1000.0));
  EXPECT_DOUBLE_EQ(defaults.max_kd_s(), kd_max);
  EXPECT_NEAR(kd_max, 5.18e-4, 1e-6);

  EXPECT_EQ(refusal(gains(2.0, 1e4, kd_max)), "");
  EXPECT_EQ(refusal(gains(0.05, 2000.0, 0.0)), "");  // the deployed servo

  const std::string kp = refusal(gains(2.0001, 0.0, 0.0));
  EXPECT_TRUE(has(kp, "servo.kp: must be <= 2 (got 2.0001)")) << kp;
  EXPECT_TRUE(has(kp, "within a tick")) << kp;  // why
  const std::string ki = refusal(gains(0.0, 10001.0, 0.0));
  EXPECT_TRUE(has(ki, "servo.ki: must be <= 10000 1/s (got 10001)")) << ki;
  EXPECT_TRUE(has(ki, "ki dt <= 1")) << ki;
  const std::string kd = refusal(gains(0.0, 0.0, 1.001 * kd_max));
  EXPECT_TRUE(has(kd, "servo.kd: must be <= 0.000518")) << kd;
  EXPECT_TRUE(has(kd, "d_filter_hz")) << kd;

  // What the probe sent, and what the structure refuses anyway.
  EXPECT_TRUE(has(refusal(gains(1e300, 0.0, 0.0)), "servo.kp"));
  EXPECT_TRUE(has(refusal(gains(0.0, 1e300, 0.0)), "servo.ki"));
  EXPECT_TRUE(has(refusal(gains(0.0, 0.0, 1e300)), "servo.kd"));
  EXPECT_TRUE(has(refusal(gains(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)), "servo.kp"));
  EXPECT_TRUE(has(refusal(gains(-0.1, 0.0, 0.0)), "servo.kp: must be >= 0"));
  // The prefix is the caller's (hystloop-ctl names its options).
  try {
    gains(3.0, 0.0, 0.0).check_bounds("");
    FAIL() << "kp 3 accepted";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "kp");
  }
}

TEST(FeedbackBounds, TheyFollowTheTickRateAndTheDerivativeFilter) {
  FeedbackGains g = gains(0.0, 19000.0, 0.0);
  EXPECT_NE(refusal(g), "");  // at 10 kHz
  g.tick_rate_hz = 2e4;
  EXPECT_EQ(refusal(g), "");
  g.ki = 20001.0;
  EXPECT_TRUE(has(refusal(g), "servo.ki: must be <= 20000 1/s"));
  FeedbackGains d = gains(0.0, 0.0, 8e-4);
  EXPECT_NE(refusal(d), "");
  d.d_filter_hz = 500.0;  // a slower filter adds less on the first tick
  EXPECT_EQ(refusal(d), "");
}

TEST(FeedbackBounds, ARunTimeChangeBeyondThemKeepsTheGainsInForce) {
  FeedbackController c(gains(0.1, 2000.0, 0.0));
  EXPECT_THROW(c.set_gains(gains(1e300, 2000.0, 0.0)), ParameterError);
  EXPECT_EQ(c.gains().kp, 0.1);
  EXPECT_EQ(c.gains().ki, 2000.0);

  // HX_CONTROL SET_GAINS kp = 1e300 reaching the bridge's core: refused there too, the gains in
  // force unchanged and the next command's correction as without the request.
  const ActuatorLimits limits;
  BridgeCore with(limits, gains(0.1, 2000.0, 0.0), 1e-4);
  BridgeCore without(limits, gains(0.1, 2000.0, 0.0), 1e-4);
  with.arm(0);
  without.arm(0);
  for (std::int64_t k = 0; k < 10; ++k) {
    if (k == 5) with.set_servo_gains(gains(1e300, 2000.0, 0.0));
    const CommandTick command{k, 10.0, 1e-7, 1, 2};
    with.submit(command);
    without.submit(command);
    const BridgeTick a = with.tick(k, 5e-8), b = without.tick(k, 5e-8);
    EXPECT_EQ(a.u_fb_V, b.u_fb_V) << k;
    EXPECT_EQ(a.u_applied_V, b.u_applied_V) << k;
  }
  EXPECT_EQ(with.servo_gains().kp, 0.1);
  EXPECT_EQ(with.servo_gains().ki, 2000.0);
}

// Where the bounds sit against Banning's stage (the simulated loop, nominal slope): beyond what
// the stage's own loop is stable with at the defaults, so they refuse only what no tuning wants.
TEST(FeedbackBounds, TheyLieBeyondTheStagesOwnStabilityLimits) {
  const ServoLoopModel stage;
  // A proportional loop: its gain margin at kp = 1 is the largest stable kp (0.40 without the
  // notch); the bound is 5x that, and the loop is unstable at it.
  const double p_only = std::pow(10.0, ServoLoopResponse(gains(1.0, 0.0, 0.0), stage).margins().gain_margin_dB / 20.0);
  EXPECT_NEAR(p_only, 0.397, 0.01);
  EXPECT_LT(ServoLoopResponse(gains(kMaxServoKp, 0.0, 0.0), stage).margins().gain_margin_dB, 0.0);
  // The deployed servo (kp 0.05, the notch at 1720 Hz, Q 0.7): its largest stable ki is below ki's
  // bound, so every ki it is stable with is accepted.
  FeedbackGains deployed = gains(0.05, 2000.0, 0.0);
  deployed.notch_hz = 1720.0;
  deployed.notch_q = 0.7;
  EXPECT_LT(largest_stable_ki(deployed, stage), deployed.max_ki_per_s());
  EXPECT_GT(largest_stable_ki(deployed, stage), 0.9 * deployed.max_ki_per_s());
}

}  // namespace
}  // namespace hystloop
