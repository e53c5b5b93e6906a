// The servo's plausibility bounds where gains enter the bridge: its configuration (servo.*, the
// bounds at the configured tick rate) and HX_CONTROL SET_GAINS, whose request outside them is
// refused naming the field, the value and the bound, the gains in force staying.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "bridge/bridge_settings.hpp"
#include "bridge/servo_request.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

std::string refusal(const std::string& yaml) {
  try {
    load_bridge_settings(Config::from_string(yaml, "bridge.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

using testing::contains;

control_t set_gains(double kp, double ki, double kd) {
  control_t m{};
  m.request_id = 1;
  m.command = control_t::SET_GAINS;
  m.target = "bridge";
  m.kp = kp;
  m.ki = ki;
  m.kd = kd;
  return m;
}

TEST(BridgeGainBounds, TheConfigsGainsAreBoundedAtItsTickRate) {
  EXPECT_EQ(refusal("servo: {kp: 2.0, ki: 10000, kd: 5.0e-4}"), "accepted");
  const std::string kp = refusal("servo: {kp: 2.5}");
  EXPECT_TRUE(contains(kp, "bridge.yaml: servo.kp: must be <= 2 (got 2.5)")) << kp;
  EXPECT_TRUE(contains(refusal("servo: {kp: 1.0e300}"), "servo.kp")) << refusal("servo: {kp: 1.0e300}");
  const std::string ki = refusal("servo: {ki: 10001}");
  EXPECT_TRUE(contains(ki, "bridge.yaml: servo.ki: must be <= 10000 1/s (got 10001)")) << ki;
  // At 20 kHz a tick is half as long: twice the ki.
  EXPECT_EQ(refusal("bridge: {rate_hz: 20000}\nservo: {ki: 20000}"), "accepted");
  EXPECT_TRUE(contains(refusal("bridge: {rate_hz: 20000}\nservo: {ki: 20001}"), "servo.ki"));
  EXPECT_TRUE(contains(refusal("servo: {kd: 6.0e-4}"), "bridge.yaml: servo.kd: must be <= 0.000518"));
  EXPECT_EQ(refusal("servo: {kd: 6.0e-4, d_filter_hz: 500}"), "accepted");  // a slower filter: a larger kd
}

TEST(BridgeGainBounds, ASetGainsBeyondThemIsRefusedNamingTheFieldAndTheGainsInForceStay) {
  const BridgeSettings s = load_bridge_settings(Config());
  FeedbackGains in_force = s.servo;
  in_force.kp = 0.1;
  in_force.ki = 2000.0;
  const FeedbackGains before = in_force;
  try {
    in_force = requested_gains(in_force, set_gains(1e300, 2000.0, 0.0));
    FAIL() << "kp 1e300 taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "servo.kp");
    EXPECT_TRUE(contains(e.what(), "must be <= 2 (got 1e+300)")) << e.what();
  }
  EXPECT_EQ(in_force.kp, before.kp);
  EXPECT_EQ(in_force.ki, before.ki);
  EXPECT_THROW(requested_gains(in_force, set_gains(0.1, 1e5, 0.0)), ParameterError);
  EXPECT_THROW(requested_gains(in_force, set_gains(0.1, 0.0, 1e-3)), ParameterError);

  // Within them: the request's gains, the rig's nominal gain, range, filter and rate.
  const FeedbackGains next = requested_gains(in_force, set_gains(2.0, 1e4, 0.0));
  EXPECT_EQ(next.kp, 2.0);
  EXPECT_EQ(next.ki, 1e4);
  EXPECT_EQ(next.nominal_gain_m_per_V, in_force.nominal_gain_m_per_V);
  EXPECT_EQ(next.tick_rate_hz, s.rate_hz);
  EXPECT_EQ(next.u_max_V, s.limits.u_max_V);
}

TEST(BridgeGainBounds, ARequestChangesOnlyTheGainsItGivesNaNKeepsTheOneInForce) {
  const double keep = std::numeric_limits<double>::quiet_NaN();
  FeedbackGains in_force;
  in_force.kp = 0.1;
  in_force.ki = 600.0;
  in_force.kd = 1e-5;
  in_force.notch_hz = 1720.0;
  in_force.notch_q = 3.0;
  control_t m = set_gains(0.2, keep, keep);
  m.notch_hz = keep;
  m.notch_q = keep;
  const FeedbackGains next = requested_gains(in_force, m);
  EXPECT_EQ(next.kp, 0.2);
  EXPECT_EQ(next.ki, 600.0);  // not 0: the old ctl sent 0 for a gain it was not given
  EXPECT_EQ(next.kd, 1e-5);
  EXPECT_EQ(next.notch_hz, 1720.0);
  EXPECT_EQ(next.notch_q, 3.0);

  m = set_gains(keep, keep, keep);
  m.notch_hz = 0.0;  // removes the notch, the gains stay
  m.notch_q = keep;
  const FeedbackGains no_notch = requested_gains(in_force, m);
  EXPECT_FALSE(no_notch.has_notch());
  EXPECT_EQ(no_notch.ki, 600.0);

  // The second notch: set beside the first (which stays), then kept by NaN.
  m = set_gains(keep, keep, keep);
  m.notch_hz = keep;
  m.notch_q = keep;
  m.notch2_hz = 2400.0;
  m.notch2_q = 3.0;
  const FeedbackGains two = requested_gains(in_force, m);
  EXPECT_EQ(two.notch_hz, 1720.0);
  EXPECT_EQ(two.notch2_hz, 2400.0);
  EXPECT_EQ(two.notch2_q, 3.0);
  m.notch2_hz = keep;
  m.notch2_q = keep;
  EXPECT_EQ(requested_gains(two, m).notch2_hz, 2400.0);

  // A partial request is bounded like a whole one.
  EXPECT_THROW(requested_gains(in_force, set_gains(keep, 1e5, keep)), ParameterError);
}

}  // namespace
}  // namespace hystloop
