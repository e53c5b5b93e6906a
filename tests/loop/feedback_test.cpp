#include "loop/feedback.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hystloop {
namespace {

TEST(Feedback, ProportionalAndIntegralInNormalisedUnits) {
  FeedbackGains g;
  g.kp = 0.5;
  g.ki = 100.0;
  g.nominal_gain_m_per_V = 1e-8;
  FeedbackController c(g);
  // e = 1 nm for one 100 us step: u = (0.5*1e-9 + 100*1e-9*1e-4) / 1e-8 V
  EXPECT_NEAR(c.update(1e-9, 0.0, 1e-4), (0.5e-9 + 1e-11) / 1e-8, 1e-12);
}

TEST(Feedback, IntegratorRemovesAConstantDisturbanceOnAUnitPlant) {
  FeedbackGains g;
  g.ki = 200.0;
  g.nominal_gain_m_per_V = 1e-8;
  FeedbackController c(g);
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
  FeedbackGains g;
  g.ki = 1000.0;
  g.nominal_gain_m_per_V = 1e-8;
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
  EXPECT_THROW(FeedbackController{g}, ParameterError);
}

}  // namespace
}  // namespace hystloop
