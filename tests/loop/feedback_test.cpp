#include "loop/feedback.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "bridge_test_rig.hpp"
#include "loop/notch_filter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using testing::servo_gains;  // kp, ki in the rig's normalisation: 1 um per 100 V

TEST(Feedback, ProportionalAndIntegralInNormalisedUnits) {
  FeedbackController c(servo_gains(0.5, 100.0));
  // e = 1 nm for one 100 us step: u = (0.5*1e-9 + 100*1e-9*1e-4) / 1e-8 V
  EXPECT_NEAR(c.update(1e-9, 0.0, 1e-4), (0.5e-9 + 1e-11) / 1e-8, 1e-12);
}

TEST(Feedback, IntegratorRemovesAConstantDisturbanceOnAUnitPlant) {
  FeedbackController c(servo_gains(0.0, 200.0));
  // Plant y = gain * u + d, reference 0: the integrator must cancel d.
  const double d = 50e-9;
  double y = d;
  for (int i = 0; i < 20000; ++i) {
    const double u = c.update(0.0 - y, 0.0, 1e-4);
    y = 1e-8 * u + d;
  }
  EXPECT_LT(std::abs(y), 1e-12);
}

TEST(Feedback, AntiWindupStopsIntegratingIntoSaturation) {
  FeedbackGains g = servo_gains(0.0, 1000.0);
  g.u_min_V = -250.0;
  g.u_max_V = 250.0;
  FeedbackController c(g);
  for (int i = 0; i < 100000; ++i) c.update(1e-6, 249.0, 1e-4);  // feedforward near the limit
  // Without anti-windup the integral would be 1e-6 * 10 s = 1e-5 m s.
  EXPECT_LT(c.integral_m_s(), 1e-10);
}

TEST(Feedback, GainChangeIsBumpless) {
  FeedbackGains g;
  g.ki = 100.0;
  FeedbackController c(g);
  for (int i = 0; i < 100; ++i) c.update(1e-8, 0.0, 1e-4);
  const double before = c.update(0.0, 0.0, 1e-4);
  g.ki = 400.0;
  c.set_gains(g);
  EXPECT_NEAR(c.update(0.0, 0.0, 1e-4), before, 1e-12);
}

TEST(Feedback, RefusesNegativeGains) {
  FeedbackGains g;
  g.ki = -1;
  EXPECT_EQ(testing::refused_field([&] { FeedbackController{g}; }), "servo.ki");
}

// The edge of the interval the caller allows, not only the actuator's range: the integral goes
// up to the edge (a nanovolt short of it) and no further.
TEST(Feedback, TheIntegratorStopsAtTheEdgeOfTheAllowedInterval) {
  FeedbackController c(servo_gains(0.0, 1000.0));
  double u = 0.0;
  for (int i = 0; i < 1000; ++i) u = c.update(1e-6, 10.0, 1e-4, -5.0, 12.0);  // +10 V per tick, 2 V allowed
  EXPECT_NEAR(10.0 + u, 12.0, 1e-7);
  EXPECT_LE(10.0 + u, 12.0);
  // The other way: an error toward the low edge takes the integral down to it.
  for (int i = 0; i < 1000; ++i) u = c.update(-1e-6, 10.0, 1e-4, -5.0, 12.0);
  EXPECT_NEAR(10.0 + u, -5.0, 1e-7);
  EXPECT_GE(10.0 + u, -5.0);
  // Inside the interval it integrates as ever: 1000 * 1e-9 * 1e-4 / 1e-8 = 0.01 V per tick.
  const double before = c.update(0.0, 0.0, 1e-4, -100.0, 100.0);
  EXPECT_NEAR(c.update(1e-9, 0.0, 1e-4, -100.0, 100.0) - before, 0.01, 1e-12);
}

// A command the proportional part alone takes beyond the edge: the integral holds (it does not
// grow toward the clamp, nor unwind: that is the error's business).
TEST(Feedback, BeyondTheEdgeAlreadyTheIntegralHolds) {
  FeedbackController c(servo_gains(1.0, 100.0));
  for (int i = 0; i < 10; ++i) c.update(1e-9, 0.0, 1e-4);
  const double held = c.integral_m_s();
  for (int i = 0; i < 100; ++i) c.update(1e-6, 0.0, 1e-4, -1.0, 1.0);  // kp e / gain = 100 V > 1 V
  EXPECT_EQ(c.integral_m_s(), held);
}

std::complex<double> response(const BiquadCoefficients& c, double f_hz, double rate_hz) {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * std::numbers::pi * f_hz / rate_hz);
  return (c.b0 + c.b1 * z1 + c.b2 * z1 * z1) / (1.0 + c.a1 * z1 + c.a2 * z1 * z1);
}

// The bilinear transform with the centre prewarped: a zero exactly at f0, unit gain at DC and
// Nyquist, and -3 dB where the transform takes the analogue band edges W (sqrt(1 + 1/4q^2) -+ 1/2q).
TEST(Notch, DesignHasItsClosedForms) {
  const double rate = 1e4;
  for (const double f0 : {50.0, 1720.0, 4400.0}) {
    for (const double q : {0.1, 0.7, 5.0, 50.0}) {
      const BiquadCoefficients c = design_notch(f0, q, rate);
      EXPECT_LT(std::abs(response(c, f0, rate)), 1e-10) << f0 << " " << q;
      EXPECT_NEAR(std::abs(response(c, 0.0, rate)), 1.0, 1e-12);
      EXPECT_NEAR(std::abs(response(c, rate / 2, rate)), 1.0, 1e-12);
      const double w = 2.0 * rate * std::tan(std::numbers::pi * f0 / rate);
      const double r = std::sqrt(1.0 + 1.0 / (4.0 * q * q));
      for (const double edge : {w * (r - 0.5 / q), w * (r + 0.5 / q)}) {
        const double f_edge = std::atan(edge / (2.0 * rate)) * rate / std::numbers::pi;
        EXPECT_NEAR(std::abs(response(c, f_edge, rate)), std::sqrt(0.5), 1e-10) << f0 << " " << q;
      }
    }
  }
}

TEST(Notch, StopsASineAtItsCentreAndPassesASlowOne) {
  const double rate = 1e4, f0 = 1720.0;
  for (const double f : {f0, 10.0}) {
    NotchFilter n(design_notch(f0, 0.7, rate));
    double peak = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double y = n.step(std::sin(2.0 * std::numbers::pi * f * i / rate));
      if (i >= 10000) peak = std::max(peak, std::abs(y));
    }
    if (f == f0) {
      EXPECT_LT(peak, 1e-9);
    } else {
      EXPECT_NEAR(peak, 1.0, 2e-3);
    }
  }
}

TEST(Notch, ServoOutputIsThePidThroughTheNotch) {
  FeedbackGains g = servo_gains(0.5, 0.0);
  g.notch_hz = 1720.0;
  g.notch_q = 0.7;
  FeedbackController c(g);
  NotchFilter n(design_notch(1720.0, 0.7, 1e4));
  for (int i = 0; i < 200; ++i) {
    const double e = 1e-9 * std::sin(0.37 * i);
    ASSERT_NEAR(c.update(e, 0.0, 1e-4), n.step(0.5 * e / 1e-8), 1e-15) << i;
  }
}

// Two notches in cascade: the servo's output is the PID through the first, then the second; a sine
// at either centre is stopped, a slow one passes.
TEST(Notch, TwoNotchesInCascadeStopEachCentre) {
  FeedbackGains g = servo_gains(0.5, 0.0);
  g.notch_hz = 780.0;
  g.notch_q = 0.5;
  g.notch2_hz = 2400.0;
  g.notch2_q = 2.0;
  FeedbackController c(g);
  NotchFilter n1(design_notch(780.0, 0.5, 1e4)), n2(design_notch(2400.0, 2.0, 1e4));
  for (int i = 0; i < 200; ++i) {
    const double e = 1e-9 * std::sin(0.37 * i);
    ASSERT_NEAR(c.update(e, 0.0, 1e-4), n2.step(n1.step(0.5 * e / 1e-8)), 1e-15) << i;
  }
  for (const double f : {780.0, 2400.0, 20.0}) {
    c.reset();
    double peak = 0.0;
    for (int i = 0; i < 40000; ++i) {
      const double u = c.update(1e-8 * std::sin(2.0 * std::numbers::pi * f * i * 1e-4), 0.0, 1e-4);
      if (i >= 30000) peak = std::max(peak, std::abs(u));
    }
    // kp e / gain: 0.5 V peak through the cascade.
    if (f == 20.0) {
      EXPECT_NEAR(peak, 0.5, 0.01) << f;
    } else {
      EXPECT_LT(peak, 1e-9) << f;
    }
  }
}

// The anti-windup holds the total command at the edge with notches in the path (the cascade's next
// output is affine in its input: b0 x + s1 over the filters). The filters' own transient may carry
// the command past the edge for a while (the bridge's clamp cuts those ticks); once it has rung
// out the command sits at the edge, not beyond it: an integral that rose in the troughs of the
// ringing, held to the next output alone, had settled 3.8 V past it with the 780 Hz notch.
TEST(Notch, TheIntegratorStopsAtTheEdgeThroughTheNotches) {
  for (const int notches : {1, 2, 3}) {
    FeedbackGains g = servo_gains(0.0, 1000.0);
    if ((notches & 1) != 0) {
      g.notch_hz = 780.0;
      g.notch_q = 0.5;
    }
    if ((notches & 2) != 0) {
      g.notch2_hz = 2400.0;
      g.notch2_q = 2.0;
    }
    FeedbackController c(g);
    double u = 0.0;
    for (int i = 0; i < 4000; ++i) {
      u = c.update(1e-6, 10.0, 1e-4, -5.0, 12.0);
      if (i >= 2000) {
        ASSERT_LE(10.0 + u, 12.0) << notches << " " << i;
      }
    }
    EXPECT_NEAR(10.0 + u, 12.0, 1e-6) << notches;
    // The settled command at the edge: ki I / gain = 2 V (without the anti-windup 4000 ticks' error).
    EXPECT_NEAR(c.integral_m_s() * 1000.0 / 1e-8, 2.0, 1e-6) << notches;
  }
}

// Switching the notch in, retuning it or out on a servo at rest changes nothing in its output.
TEST(Notch, ANotchChangeIsBumpless) {
  FeedbackGains g = servo_gains(0.0, 300.0);
  FeedbackController c(g);
  for (int i = 0; i < 1000; ++i) c.update(1e-8, 0.0, 1e-4);
  const double before = c.update(0.0, 0.0, 1e-4);
  ASSERT_GT(before, 1.0);
  for (const double f : {1720.0, 900.0, 0.0, 2500.0}) {
    g.notch_hz = f;
    c.set_gains(g);
    for (int i = 0; i < 50; ++i) ASSERT_NEAR(c.update(0.0, 0.0, 1e-4), before, 1e-12) << f << " " << i;
  }
  // The second notch likewise, beside the first.
  for (const double f : {2400.0, 700.0, 0.0}) {
    g.notch2_hz = f;
    c.set_gains(g);
    for (int i = 0; i < 50; ++i) ASSERT_NEAR(c.update(0.0, 0.0, 1e-4), before, 1e-12) << "2: " << f << " " << i;
  }
}

// Switching the second notch in on a running servo leaves the first's state as it was (a ringing
// filter reset would jump); the new one starts settled at the first's last output.
TEST(Notch, ChangingOneNotchKeepsTheOthersState) {
  FeedbackGains g = servo_gains(0.5, 0.0);
  g.notch_hz = 780.0;
  g.notch_q = 0.5;
  FeedbackController c(g);
  NotchFilter first(design_notch(780.0, 0.5, 1e4));
  double first_out = 0.0;
  const auto error = [](int i) { return 1e-9 * std::sin(0.37 * i) + 2e-10 * std::sin(1.9 * i); };
  for (int i = 0; i < 300; ++i) {
    first_out = first.step(0.5 * error(i) / 1e-8);
    ASSERT_NEAR(c.update(error(i), 0.0, 1e-4), first_out, 1e-15) << i;
  }
  g.notch2_hz = 2400.0;
  g.notch2_q = 3.0;
  c.set_gains(g);
  NotchFilter second(design_notch(2400.0, 3.0, 1e4));
  second.settle_at(first_out);
  for (int i = 300; i < 600; ++i) {
    ASSERT_NEAR(c.update(error(i), 0.0, 1e-4), second.step(first.step(0.5 * error(i) / 1e-8)), 1e-15) << i;
  }
}

TEST(Notch, RefusesANotchOutsideItsRangeNamingTheField) {
  FeedbackGains g;  // 10 kHz: the notch must be below 4.5 kHz
  g.notch_hz = 4500.0;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch_hz");
  g.notch_hz = -1.0;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch_hz");
  g.notch_hz = 4499.0;
  EXPECT_NO_THROW(g.validate());
  g.tick_rate_hz = 2000.0;  // the limit follows the clock
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch_hz");
  g.tick_rate_hz = 1e4;
  g.notch_q = 0.09;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch_q");
  g.notch_q = 51.0;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch_q");
  // No notch, Q unused: what a SET_GAINS of a sender that knows no notch carries (0, 0).
  g.notch_hz = 0.0;
  g.notch_q = 0.0;
  EXPECT_NO_THROW(g.validate());
  // The second notch is held to the same bounds under its own names.
  g.notch2_hz = 4500.0;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch2_hz");
  g.notch2_hz = 2400.0;
  g.notch2_q = 60.0;
  EXPECT_EQ(testing::refused_field([&] { g.validate(); }), "servo.notch2_q");
  g.notch2_q = 2.0;
  EXPECT_NO_THROW(g.validate());
}

TEST(Notch, NotchesAreNamedAsTheyAreSet) {
  FeedbackGains g;
  EXPECT_EQ(notches_text(g), "no notch");
  g.notch2_hz = 2400.0;
  EXPECT_EQ(notches_text(g), "notch at 2400 Hz (Q 2)");
  g.notch_hz = 780.0;
  g.notch_q = 0.5;
  EXPECT_EQ(notches_text(g), "notches at 780 Hz (Q 0.5) and 2400 Hz (Q 2)");
}

}  // namespace
}  // namespace hystloop
