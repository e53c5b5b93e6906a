#include "models/stage_inverse.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/smooth_signal.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;  // the bridge's tick

TEST(StageInverse, BanningStageHasItsSamplingZeroNearMinusOneAndUnitDcGain) {
  const DiscreteStage d = discretise_zoh(SecondOrderStageParams{}, kDt);
  EXPECT_NEAR(d.sampling_zero(), -0.93, 0.01);
  EXPECT_NEAR((d.b1 + d.b2) / (1.0 + d.a1 + d.a2), 1.0, 1e-12);
  EXPECT_NEAR(d.magnitude(0.0, kDt), 1.0, 1e-12);
}

TEST(StageInverse, DiscretisationMatchesTheContinuousResponseAtLowFrequency) {
  // Far below the resonance the ZOH model's magnitude is the continuous |k / (k - w^2 + i c w)|
  // times the hold's own sin(w dt / 2) / (w dt / 2) (what aliases back is of higher order).
  const SecondOrderStageParams p;
  const DiscreteStage d = discretise_zoh(p, kDt);
  for (const double f : {10.0, 100.0, 300.0}) {
    const double w = 2.0 * std::numbers::pi * f;
    const double hold = std::sin(0.5 * w * kDt) / (0.5 * w * kDt);
    const double continuous = hold * p.k / std::abs(std::complex<double>(p.k - w * w, p.c * w));
    EXPECT_NEAR(d.magnitude(f, kDt), continuous, 3e-4 * continuous) << f;  // 1.8e-4 at 300 Hz; 1.3e-3 without the hold
  }
}

TEST(StageInverse, DrivenByItTheStageReproducesASmoothReferenceAtEverySample) {
  std::mt19937_64 rng(11);
  for (const SecondOrderStageParams p :
       {SecondOrderStageParams{}, SecondOrderStageParams{4e7, 6e3}, SecondOrderStageParams{3e8, 1.5e3}}) {
    const std::vector<double> r = testing::smooth_signal(rng, 1e-6, 0.2e-6, 20000);
    StageInverse inverse(p, kDt);
    SecondOrderStage stage(p);
    inverse.reset(r[0]);
    stage.reset(r[0]);
    double worst = 0.0;
    for (const double rk : r) {
      const double y = stage.step(inverse.step(rk), kDt);  // y at the end of the tick
      worst = std::max(worst, std::abs(y - rk));
    }
    EXPECT_LT(worst, 1e-9 * 1.2e-6) << "k " << p.k << " c " << p.c;
  }
}

TEST(StageInverse, AtHalfTheTickRateTheInputStaysWithinTheInverseGain) {
  // The worst reference for this inverse alternates every tick: its one pole (the sampling zero)
  // sits there. The input is bounded by |G^-1(-1)| times the amplitude plus the decaying transient.
  const SecondOrderStageParams p;
  const DiscreteStage d = discretise_zoh(p, kDt);
  const double gain_at_nyquist = std::abs((1.0 - d.a1 + d.a2) / (d.b2 - d.b1));
  StageInverse inverse(p, kDt);
  double worst_late = 0.0, worst = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const double w = inverse.step(k % 2 == 0 ? 1e-9 : -1e-9);
    ASSERT_TRUE(std::isfinite(w));
    worst = std::max(worst, std::abs(w));
    if (k > 2000) worst_late = std::max(worst_late, std::abs(w));
  }
  EXPECT_NEAR(worst_late, gain_at_nyquist * 1e-9, 1e-3 * gain_at_nyquist * 1e-9);
  EXPECT_LT(worst, 2.0 * gain_at_nyquist * 1e-9);
}

TEST(StageInverse, RefusesAStageWhoseSamplingZeroIsTooCloseToTheUnitCircle) {
  // Almost undamped: the ZOH zero tends to -1 and the inverse would ring for ever.
  SecondOrderStageParams p;
  p.c = 1e-3;
  try {
    StageInverse inverse(p, kDt);
    FAIL() << "accepted a stage with sampling zero " << discretise_zoh(p, kDt).sampling_zero();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("stage.c"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sampling zero"), std::string::npos) << e.what();
  }
  EXPECT_THROW(StageInverse(SecondOrderStageParams{-1.0, 2e3}, kDt), ParameterError);
  EXPECT_THROW(StageInverse(SecondOrderStageParams{}, 0.0), ParameterError);
}

TEST(StageInverse, RestsWhereItWasResetAndHoldsOnANonFiniteReference) {
  StageInverse inverse(SecondOrderStageParams{}, kDt);
  inverse.reset(0.5e-6);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(inverse.step(0.5e-6), 0.5e-6, 1e-18);
  const double before = inverse.last_input();
  EXPECT_EQ(inverse.step(std::nan("")), before);
  EXPECT_NEAR(inverse.step(0.5e-6), 0.5e-6, 1e-18);
}

TEST(StageInverse, StepsWithoutAllocating) {
  StageInverse inverse(SecondOrderStageParams{}, kDt);
  testing::AllocationCounter allocations;
  double sum = 0.0;
  for (int k = 0; k < 1000; ++k) sum += inverse.step(1e-9 * std::sin(0.01 * k));
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace hystloop
