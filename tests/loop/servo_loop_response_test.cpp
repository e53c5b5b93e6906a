// The servo loop's frequency-response analysis against the things it models: the stage's
// response to a sine is what SecondOrderStage does, and the stability limit it finds for ki is
// where BridgeCore's servo on that stage starts to ring up, with and without the notch.
#include "loop/servo_loop_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "loop/bridge_core.hpp"
#include "models/second_order_stage.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;

// kp = 1, ki = 0, unit gains: L is the stage's ZOH response alone.
FeedbackGains unit_proportional() {
  FeedbackGains g;
  g.kp = 1.0;
  g.nominal_gain_m_per_V = 1.0;
  return g;
}

// The stage driven by u_k = cos(w k dt) from rest: the position reaching tick k (the end of tick
// k - 1), fitted in the steady state as Re(H e^{j w k dt}).
std::complex<double> measured_stage_response(double f_hz) {
  SecondOrderStage stage;
  const double w = 2.0 * std::numbers::pi * f_hz * kDt;
  double y = 0.0;
  std::complex<double> sum = 0.0;
  int n = 0;
  for (int k = 0; k < 200000; ++k) {
    if (k >= 100000) {  // the transient (decay rate c/2 = 1015 1/s) is long gone
      sum += y * std::polar(1.0, -w * k);
      ++n;
    }
    y = stage.step(std::cos(w * k), kDt);
  }
  return 2.0 * sum / static_cast<double>(n);
}

TEST(ServoLoopResponse, TheStageIsTheSimulatorsStage) {
  const ServoLoopResponse r(unit_proportional());
  for (const double f : {13.0, 300.0, 1650.0, 1721.0, 3100.0}) {
    const std::complex<double> want = measured_stage_response(f);
    EXPECT_LT(std::abs(r.loop_gain(f) - want), 1e-3 * std::abs(want)) << f << " Hz";
  }
  // One more tick of delay is a factor e^{-j w dt}.
  ServoLoopModel late;
  late.extra_delay_ticks = 1;
  const std::complex<double> ratio = ServoLoopResponse(unit_proportional(), late).loop_gain(400.0) / r.loop_gain(400.0);
  EXPECT_NEAR(std::arg(ratio), -2.0 * std::numbers::pi * 400.0 * kDt, 1e-12);
  EXPECT_NEAR(std::abs(ratio), 1.0, 1e-12);
}

// How much the error of a 1 nm step in the reference grows from [0.05, 0.1) s to [0.45, 0.5) s
// with BridgeCore's servo on the linear stage (the gain exactly the servo's nominal one).
double growth(const FeedbackGains& gains) {
  ActuatorLimits lim;
  lim.slew_V_per_s = 1e9;
  lim.watchdog_s = 1.0;
  BridgeCore bridge(lim, gains, kDt);
  SecondOrderStage stage;
  bridge.arm(0);
  double y = 0.0, early = 0.0, late = 0.0;
  for (std::int64_t k = 0; k < 5000; ++k) {
    bridge.submit({k, 0.0, 1e-9, 1, 0});
    const BridgeTick t = bridge.tick(k, y);
    y = gains.nominal_gain_m_per_V * stage.step(t.u_applied_V, kDt);
    const double e = std::abs(1e-9 - y);
    if (k >= 500 && k < 1000) early = std::max(early, e);
    if (k >= 4500) late = std::max(late, e);
  }
  return late / early;
}

TEST(ServoLoopResponse, TheStabilityLimitIsWhereTheServoRingsUp) {
  for (const double notch_hz : {0.0, 1720.0}) {
    FeedbackGains g;
    g.kp = 0.1;
    g.nominal_gain_m_per_V = 6.3e-9;
    g.notch_hz = notch_hz;
    g.notch_q = 0.7;
    const double ki_max = largest_stable_ki(g, ServoLoopModel{});
    ASSERT_GT(ki_max, 1000.0);
    ASSERT_LT(ki_max, 1e5);
    g.ki = 0.97 * ki_max;
    EXPECT_TRUE(ServoLoopResponse(g).margins().stable);
    EXPECT_LT(growth(g), 1.0) << "notch " << notch_hz << " Hz, ki " << g.ki;
    g.ki = 1.03 * ki_max;
    EXPECT_FALSE(ServoLoopResponse(g).margins().stable);
    EXPECT_GT(growth(g), 1.0) << "notch " << notch_hz << " Hz, ki " << g.ki;
  }
}

// Banning's stage at 10 kHz: ki >= 2000 1/s (kp 0.1) is unstable without a notch, and the notch
// moves the limit several times higher.
TEST(ServoLoopResponse, TheNotchRaisesTheLimitOnBanningsStage) {
  FeedbackGains g;
  g.kp = 0.1;
  const double plain = largest_stable_ki(g, ServoLoopModel{});
  g.notch_hz = 1720.0;
  g.notch_q = 0.7;
  const double notched = largest_stable_ki(g, ServoLoopModel{});
  EXPECT_GT(plain, 1000.0);
  EXPECT_LT(plain, 2000.0);
  EXPECT_GT(notched, 4.0 * plain);
}

TEST(ServoLoopResponse, MarginsOfAStableLoopAreConsistent) {
  FeedbackGains g;
  g.kp = 0.1;
  g.ki = 600.0;
  const ServoLoopResponse r(g);
  const LoopMargins m = r.margins();
  ASSERT_TRUE(m.stable);
  // At the gain crossover |L| = 1 and the phase margin is the angle from -1; at the phase
  // crossover L is real and negative, 1 / |L| the gain margin.
  EXPECT_NEAR(std::abs(r.loop_gain(m.crossover_hz)), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(r.loop_gain(m.gain_margin_hz).imag()), 0.0, 1e-9);
  EXPECT_LT(r.loop_gain(m.gain_margin_hz).real(), 0.0);
  EXPECT_NEAR(-20.0 * std::log10(std::abs(r.loop_gain(m.gain_margin_hz))), m.gain_margin_dB, 1e-9);
  // ki is about the crossover in rad/s: 600 1/s ~ 95 Hz.
  EXPECT_NEAR(m.crossover_hz, 600.0 / (2.0 * std::numbers::pi), 10.0);
  // At the phase crossover |1 + L| = 1 - 10^(-GM / 20): the peak of |S| is no lower (to the grid's step).
  EXPECT_GE(1.01 * m.sensitivity_peak, 1.0 / (1.0 - std::pow(10.0, -m.gain_margin_dB / 20.0)));
}

// Any stage: Banning's written as a linear stage gives Banning's loop, and a lightly damped mode
// the servo's notch is not at makes the product's defaults unstable (why deploy/config/two-mode
// has a servo of its own) where a notch on that mode makes them stable again.
TEST(ServoLoopResponse, AnyLinearStageGivesItsLoop) {
  FeedbackGains g;
  g.kp = 0.05;
  g.ki = 2000.0;
  g.notch_hz = 1720.0;
  g.notch_q = 0.7;
  g.nominal_gain_m_per_V = 1.0;
  ServoLoopModel banning;
  ServoLoopModel as_linear;
  as_linear.linear = LinearStageSpec::second_order(banning.stage.k, banning.stage.c);
  for (const double f : {10.0, 300.0, 1000.0, 4000.0}) {  // not at the notch, where L is 0 to rounding
    const std::complex<double> a = ServoLoopResponse(g, banning).loop_gain(f);
    const std::complex<double> b = ServoLoopResponse(g, as_linear).loop_gain(f);
    EXPECT_NEAR(std::abs(a - b), 0.0, 1e-9 * std::abs(a)) << f;
  }
  ServoLoopModel two_mode;
  two_mode.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5e-4);
  g.kp = 0.2;                                             // a servo meant to do something at line rates
  EXPECT_FALSE(ServoLoopResponse(g, two_mode).stable());  // the 780 Hz mode, |P| ~ 17, unnotched
  g.notch_hz = 780.0;
  g.notch_q = 0.5;
  const ServoLoopResponse notched(g, two_mode);
  ASSERT_TRUE(notched.stable());
  EXPECT_GT(notched.margins().gain_margin_dB, 0.0);
}

TEST(ServoLoopResponse, RefusesAModelNamingTheField) {
  ServoLoopModel m;
  m.slope_ratio = 0.0;
  EXPECT_EQ(testing::refused_field([&] { ServoLoopResponse(FeedbackGains{}, m); }), "loop.slope_ratio");
  m = {};
  m.extra_delay_ticks = -1;
  EXPECT_EQ(testing::refused_field([&] { ServoLoopResponse(FeedbackGains{}, m); }), "loop.extra_delay_ticks");
}

}  // namespace
}  // namespace hystloop
