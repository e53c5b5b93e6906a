// hystloop-ctl gains' margin check: the deployed servo on Banning's stage passes; the same gains
// on the two-mode stage (780 Hz and 2.4 kHz modes, 1.5 ticks of delay) are unstable, and a notch
// on its first mode makes them stable with a phase margin under the 40 degrees a servo should
// keep (bench/servo_margins --two-mode prints the same loop's figures).
#include "ctl_servo_check.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"

namespace hystloop::ctl {
namespace {

ServoGainsFigures deployed(double notch_hz = 1720.0, double notch_q = 0.7) {
  return {0.05, 2000.0, 0.0, notch_hz, notch_q};  // deploy/config/bridge.yaml
}

StageModel two_mode() {
  StageModel s;
  s.kind = StageModel::Kind::kLinear;
  s.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5e-4);
  return s;
}

TEST(CtlServoCheck, TheDeployedServoOnBanningsStageKeepsItsMargins) {
  StageModel banning;
  banning.kind = StageModel::Kind::kSecondOrder;
  const auto model = servo_loop_model(banning, 1e-4, 0);
  ASSERT_TRUE(model);
  const ServoCheck c = check_servo(deployed(), *model);
  EXPECT_TRUE(c.stable());
  EXPECT_GE(c.margins.gain_margin_dB, kMinGainMargin_dB);
  EXPECT_GE(c.margins.phase_margin_deg, kMinPhaseMargin_deg);
  EXPECT_TRUE(c.warnings.empty()) << c.warnings.front();
  EXPECT_EQ(describe_margins(c.margins).find("UNSTABLE"), std::string::npos);
}

TEST(CtlServoCheck, TheSameGainsOnTheTwoModeStageAreUnstable) {
  const auto model = servo_loop_model(two_mode(), 1e-4, 0);
  ASSERT_TRUE(model);
  const ServoCheck c = check_servo(deployed(), *model);
  EXPECT_FALSE(c.stable());
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("UNSTABLE"), std::string::npos) << c.warnings[0];
  EXPECT_EQ(describe_margins(c.margins).rfind("UNSTABLE: ", 0), 0u);
}

TEST(CtlServoCheck, ANotchOnTheFirstModeIsStableButShortOfPhase) {
  const auto model = servo_loop_model(two_mode(), 1e-4, 0);
  ASSERT_TRUE(model);
  const ServoCheck c = check_servo(deployed(780.0, 0.5), *model);
  ASSERT_TRUE(c.stable());
  EXPECT_GE(c.margins.gain_margin_dB, kMinGainMargin_dB);
  EXPECT_LT(c.margins.phase_margin_deg, kMinPhaseMargin_deg);
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_NE(c.warnings[0].find("phase margin"), std::string::npos) << c.warnings[0];
  // A card's read after its write costs phase: a tick more of delay only lowers the margin.
  const ServoCheck card = check_servo(deployed(780.0, 0.5), *servo_loop_model(two_mode(), 1e-4, 1));
  EXPECT_LT(card.stable() ? card.margins.phase_margin_deg : -1.0, c.margins.phase_margin_deg);
}

TEST(CtlServoCheck, AStageWithoutDynamicsHasNothingToCheckAndBadTicksAreRefused) {
  EXPECT_FALSE(servo_loop_model(StageModel{}, 1e-4, 0));
  EXPECT_THROW(servo_loop_model(two_mode(), -1.0, 0), ParameterError);
  EXPECT_THROW(servo_loop_model(two_mode(), 1e-4, -1), ParameterError);
}

}  // namespace
}  // namespace hystloop::ctl
