// Notches suggested from a stage model (loop/servo_notches.hpp): one per resonant mode, the most
// resonant first, wide enough to hold the peak down 10 % off; and what they buy the servo on the
// two-mode stage the product's defaults are unstable on.
#include "loop/servo_notches.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "loop/servo_loop_response.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

constexpr double kRate_hz = 1e4;

LinearStageSpec two_mode() {
  return LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5e-4);
}

// The analogue notch's gain at r times its centre.
double notch_gain(double r, double q) {
  const double gap = 1.0 - r * r;
  return std::abs(gap) / std::sqrt(gap * gap + (r / q) * (r / q));
}

TEST(ServoNotches, OnePerResonantModeTheMostResonantFirst) {
  const std::vector<ModeNotch> n = notches_for_stage(two_mode(), kRate_hz);
  ASSERT_EQ(n.size(), 2U);
  // Each mode's frequency: the pole's modulus, the mode's natural frequency.
  EXPECT_NEAR(n[0].notch.hz, 780.0, 1e-6);
  EXPECT_NEAR(n[0].damping, 0.03, 1e-9);
  EXPECT_NEAR(n[1].notch.hz, 2400.0, 1e-6);
  EXPECT_NEAR(n[1].damping, 0.02, 1e-9);
  // The peak is the model's gain there against its DC gain: the 780 Hz mode's residue over 2 zeta
  // (0.92 / 0.06 ~ 15) give or take the other mode; the small mode's is a few.
  EXPECT_NEAR(n[0].peak_gain, std::abs(two_mode().frequency_response(780.0)), 1e-9);
  EXPECT_GT(n[0].peak_gain, 12.0);
  EXPECT_LT(n[1].peak_gain, n[0].peak_gain);
  EXPECT_GT(n[1].peak_gain, 1.0);
  // The width: 10 % off the centre the notch takes the peak to unity (Q within its clamp).
  for (const ModeNotch& m : n) {
    if (m.notch.q > kNotchMinQ && m.notch.q < kNotchMaxSuggestedQ) {
      EXPECT_NEAR(notch_gain(1.1, m.notch.q) * m.peak_gain, 1.0, 1e-9) << m.notch.hz;
    }
  }
  EXPECT_LT(n[0].notch.q, n[1].notch.q);  // the stronger peak gets the wider notch
}

TEST(ServoNotches, BanningsStageHasOneAndAWellDampedStageNone) {
  const LinearStageSpec banning = LinearStageSpec::second_order(1.17e8, 2.03e3);  // Table 2: 1.72 kHz, zeta 0.094
  const std::vector<ModeNotch> n = notches_for_stage(banning, kRate_hz);
  ASSERT_EQ(n.size(), 1U);
  EXPECT_NEAR(n[0].notch.hz, std::sqrt(1.17e8) / (2.0 * std::numbers::pi), 1e-6);
  EXPECT_NEAR(n[0].damping, 2.03e3 / (2.0 * std::sqrt(1.17e8)), 1e-9);
  EXPECT_TRUE(notches_for_stage(LinearStageSpec::sum_of_modes({{800.0, 0.5, 1.0}}), kRate_hz).empty());
  // A mode at or above 0.45 of the tick rate gets none (a notch there would be a band-stop at Nyquist).
  EXPECT_TRUE(notches_for_stage(LinearStageSpec::sum_of_modes({{4600.0, 0.02, 1.0}}), kRate_hz).empty());
  // Three resonant modes: the servo has two notches, for the two highest peaks.
  const std::vector<ModeNotch> three = notches_for_stage(
      LinearStageSpec::sum_of_modes({{500.0, 0.05, 0.5}, {1200.0, 0.01, 0.3}, {3000.0, 0.05, 0.2}}), kRate_hz);
  ASSERT_EQ(three.size(), kServoNotches);
  EXPECT_NEAR(three[0].notch.hz, 1200.0, 1e-6);
  EXPECT_NEAR(three[1].notch.hz, 500.0, 1e-6);
}

// The same poles from a discrete model (form (d)): mapped back by ln(z) / dt.
TEST(ServoNotches, ADiscreteModelGivesTheSameNotches) {
  const DiscreteLinearStage d = discretise(two_mode(), 1.0 / kRate_hz);
  std::vector<double> num(d.numerator.data(), d.numerator.data() + d.numerator.size());
  std::vector<double> den(d.denominator.data(), d.denominator.data() + d.denominator.size());
  const std::vector<ModeNotch> n = notches_for_stage(LinearStageSpec::discrete(num, den, 1.0 / kRate_hz), kRate_hz);
  ASSERT_EQ(n.size(), 2U);
  EXPECT_NEAR(n[0].notch.hz, 780.0, 1e-3);
  EXPECT_NEAR(n[1].notch.hz, 2400.0, 1e-3);
}

// The notches suggested for the two-mode stage make an integral servo there hold the margins a lab
// wants (6 dB, 40 deg) in the simulator's loop and on a card that reads a tick later; without them
// the same servo is unstable.
TEST(ServoNotches, TheySteadyAnIntegralServoOnTheTwoModeStage) {
  FeedbackGains g;
  g.kp = 0.0;
  g.ki = 800.0;  // deploy/config/two-mode/bridge.yaml
  g.nominal_gain_m_per_V = 1.0;
  ServoLoopModel model;
  model.linear = two_mode();
  EXPECT_FALSE(ServoLoopResponse(g, model).stable());
  const std::vector<ModeNotch> n = notches_for_stage(two_mode(), kRate_hz);
  set_notches(g, n);
  EXPECT_EQ(g.notch_hz, n[0].notch.hz);
  EXPECT_EQ(g.notch2_q, n[1].notch.q);
  for (const int card : {0, 1}) {
    model.extra_delay_ticks = card;
    const LoopMargins m = ServoLoopResponse(g, model).margins();
    ASSERT_TRUE(m.stable) << card;
    EXPECT_GE(m.gain_margin_dB, 6.0) << card;
    EXPECT_GE(m.phase_margin_deg, 40.0) << card;
  }
  set_notches(g, {});
  EXPECT_EQ(g.notch_hz, 0.0);
  EXPECT_EQ(g.notch2_hz, 0.0);
}

// The servo suggested for a stage: its notches, kp 0 and the largest integral gain that keeps
// 10 dB and 50 deg at both ends of the hysteresis' slope, on stages of other classes too (a single
// low mode with 2.5 ticks of delay, a non-minimum-phase zero): the design holds at both slopes, and
// 2 % more integral gain would break it (the largest, not merely a safe one).
TEST(ServoNotches, TheSuggestedServoKeepsItsMarginsAtBothSlopesAndIsTheLargest) {
  const LinearStageSpec stages[] = {
      two_mode(),
      LinearStageSpec::sum_of_modes({{450.0, 0.02, 1.0}}, 2.5e-4),
      LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-55.0, 1100.0}}, 1e-4),
  };
  for (const LinearStageSpec& stage : stages) {
    for (const int card : {0, 1}) {
      FeedbackGains base;
      base.kp = 0.3;  // taken out: kp 0
      const StageServo s = servo_for_stage(stage, base, card);
      EXPECT_EQ(s.gains.kp, 0.0);
      ASSERT_GT(s.gains.ki, 0.0) << card;
      EXPECT_EQ(s.gains.notch_hz, s.notches.empty() ? 0.0 : s.notches[0].notch.hz);
      ServoLoopModel model;
      model.linear = stage;
      model.extra_delay_ticks = card;
      bool all_hold = true;
      FeedbackGains more = s.gains;
      more.ki *= 1.02;  // past the bisection's bracket (0.5 %) and the rounding down to a whole 1/s
      bool more_holds = true;
      for (const double slope : kServoDesignSlopeRatios) {
        model.slope_ratio = slope;
        const LoopMargins m = ServoLoopResponse(s.gains, model).margins();
        all_hold = all_hold && m.stable && m.gain_margin_dB >= kServoDesignGainMargin_dB &&
                   m.phase_margin_deg >= kServoDesignPhaseMargin_deg;
        const LoopMargins n = ServoLoopResponse(more, model).margins();
        more_holds = more_holds && n.stable && n.gain_margin_dB >= kServoDesignGainMargin_dB &&
                     n.phase_margin_deg >= kServoDesignPhaseMargin_deg;
      }
      EXPECT_TRUE(all_hold) << s.gains.ki << " card " << card;
      EXPECT_FALSE(more_holds) << s.gains.ki << " card " << card;
      EXPECT_GE(s.worst.gain_margin_dB, kServoDesignGainMargin_dB);
      EXPECT_GE(s.worst.phase_margin_deg, kServoDesignPhaseMargin_deg);
    }
  }
  // The two-mode stage's: its modes notched, and an integral gain near the hand-tuned 800 1/s of
  // deploy/config/two-mode (14.5 dB / 58 deg in the simulator).
  const StageServo two = servo_for_stage(two_mode(), FeedbackGains{});
  ASSERT_EQ(two.notches.size(), 2U);
  EXPECT_GT(two.gains.ki, 400.0);
  EXPECT_LT(two.gains.ki, 3000.0);
}

TEST(ServoNotches, ABadModelIsRefusedNamingTheField) {
  EXPECT_EQ(testing::refused_field([] {
              notches_for_stage(LinearStageSpec::sum_of_modes({{780.0, -0.03, 1.0}}), kRate_hz);
            }).substr(0, 6),
            "stage.");
}

}  // namespace
}  // namespace hystloop
