// The servo's defaults in deploy/config/bridge.yaml keep the margins docs/TRACKING.md gives them
// on Banning's stage (bench/servo_margins prints the table): the loop as the simulator runs it,
// as a card that reads after writing runs it, and when the resonance or the stage's local slope
// (the hysteresis moves it between 0.57 and 1.36 x the nominal gain) is not as assumed.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bridge/bridge_settings.hpp"
#include "loop/servo_loop_response.hpp"
#include "loop/servo_notches.hpp"

namespace hystloop {
namespace {

ServoLoopModel model_of(const BridgeSettings& s, double resonance_scale = 1.0, double slope = 1.0, int delay = 0) {
  ServoLoopModel m;
  m.stage = s.stage.banning.stage;
  m.stage.k *= resonance_scale * resonance_scale;
  m.stage.c *= resonance_scale;  // the same damping ratio
  m.dt_s = s.dt_s();
  m.slope_ratio = slope;
  m.extra_delay_ticks = delay;
  return m;
}

BridgeSettings deployed() {
  return load_bridge_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge.yaml"));
}

TEST(BridgeServoMargins, TheDefaultsKeepTheirMargins) {
  const BridgeSettings s = deployed();
  ASSERT_TRUE(s.servo.has_notch());
  const ServoLoopResponse sim(s.servo, model_of(s));
  const LoopMargins m = sim.margins();
  ASSERT_TRUE(m.stable);
  EXPECT_GE(m.gain_margin_dB, 12.0);      // 13.4 dB
  EXPECT_GE(m.phase_margin_deg, 75.0);    // 80°
  EXPECT_LE(sim.sensitivity(50.0), 0.2);  // 0.156: a third of the former defaults' 0.454
  const LoopMargins card = ServoLoopResponse(s.servo, model_of(s, 1.0, 1.0, 1)).margins();
  ASSERT_TRUE(card.stable);
  EXPECT_GE(card.gain_margin_dB, 9.0);     // 9.7 dB
  EXPECT_GE(card.phase_margin_deg, 60.0);  // 68°
}

TEST(BridgeServoMargins, TheDefaultsStayStableWhenTheStageIsNotAsAssumed) {
  const BridgeSettings s = deployed();
  for (const double resonance : {0.9, 1.0, 1.1}) {
    for (const double slope : {0.57, 1.0, 1.36}) {
      for (const int delay : {0, 1}) {
        const LoopMargins m = ServoLoopResponse(s.servo, model_of(s, resonance, slope, delay)).margins();
        ASSERT_TRUE(m.stable) << resonance << " " << slope << " " << delay;
        EXPECT_GE(m.gain_margin_dB, 5.0) << resonance << " " << slope << " " << delay;  // 5.4 dB at worst
        EXPECT_GE(m.phase_margin_deg, 45.0) << resonance << " " << slope << " " << delay;
      }
    }
  }
}

// Without its notch the same ki is unstable: the notch is what lets the servo go this fast.
TEST(BridgeServoMargins, TheDefaultKiNeedsTheNotch) {
  const BridgeSettings s = deployed();
  FeedbackGains plain = s.servo;
  plain.notch_hz = 0.0;
  EXPECT_FALSE(ServoLoopResponse(plain, model_of(s)).stable());
  EXPECT_LT(largest_stable_ki(plain, model_of(s)), s.servo.ki);
  EXPECT_GT(largest_stable_ki(s.servo, model_of(s, 1.0, 1.0, 1)), 2.5 * s.servo.ki);
}

// deploy/config/two-mode's servo on the stage that config simulates (its own plant.stage): the
// margins a lab wants, in the simulator's loop and on a card that reads a tick later, and both
// notches where the identified model puts them (loop/servo_notches.hpp).
TEST(BridgeServoMargins, TheTwoModeStagesServoHoldsSixDecibelsAndFortyDegrees) {
  const BridgeSettings s =
      load_bridge_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/two-mode/bridge.yaml"));
  ASSERT_EQ(s.backend, "series");
  const FeedbackGains& g = s.servo_of(0);
  ASSERT_TRUE(g.has_notch() && g.has_notch2());
  const std::vector<ModeNotch> want = notches_for_stage(s.stage.linear, 1.0 / s.dt_s());
  ASSERT_EQ(want.size(), 2U);
  EXPECT_NEAR(g.notch_hz, want[0].notch.hz, 1e-6);
  EXPECT_NEAR(g.notch_q, want[0].notch.q, 0.01);
  EXPECT_NEAR(g.notch2_hz, want[1].notch.hz, 1e-6);
  EXPECT_NEAR(g.notch2_q, want[1].notch.q, 0.05);
  for (const int delay : {0, 1}) {
    ServoLoopModel m;
    m.linear = s.stage.linear;
    m.dt_s = s.dt_s();
    m.extra_delay_ticks = delay;
    const LoopMargins margins = ServoLoopResponse(g, m).margins();
    ASSERT_TRUE(margins.stable) << delay;
    EXPECT_GE(margins.gain_margin_dB, 6.0) << delay;     // 14.5 / 11.8 dB
    EXPECT_GE(margins.phase_margin_deg, 40.0) << delay;  // 58 / 54 deg
  }
}

}  // namespace
}  // namespace hystloop
