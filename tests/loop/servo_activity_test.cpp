// What the planner reads of the servo's recent work (loop/servo_share.hpp, ServoActivity): its
// reach above and below the feedforward, and its steps along the feedforward's fast ones only,
// each decaying over kMemory_s.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "loop/servo_share.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;
constexpr double kFast = 2.0;  // [V per tick]

CompensatorInput sample(std::int64_t k, double u_ff, double fb) { return {k, u_ff + fb, 0.0, u_ff}; }

TEST(ServoActivity, CountsTheServosStepsAlongTheFeedforwardsFastOnesOnly) {
  ServoActivity a;
  a.observe(sample(0, 0.0, 0.0), kDt, kFast);
  a.observe(sample(1, 3.0, 0.4), kDt, kFast);  // fast up, the servo up 0.4: along
  EXPECT_NEAR(a.step_along_peak_V(), 0.4, 1e-12);
  a.observe(sample(2, 6.0, 0.0), kDt, kFast);  // fast up, the servo down 0.4: against, nothing taken
  EXPECT_NEAR(a.step_along_peak_V(), 0.4 * std::exp(-kDt / ServoActivity::kMemory_s), 1e-12);
  a.observe(sample(3, 6.5, 1.0), kDt, kFast);  // slow: a step of 1 V is not counted
  EXPECT_LT(a.step_along_peak_V(), 0.4);
  a.observe(sample(4, 3.5, 0.0), kDt, kFast);  // fast down, the servo down 1 V: along
  EXPECT_NEAR(a.step_along_peak_V(), 1.0, 1e-12);
  EXPECT_NEAR(a.above_peak_V(), 1.0, 1e-3);
  EXPECT_EQ(a.below_peak_V(), 0.0);
  // A gap: the step across it is not a tick's.
  a.reset();
  a.observe(sample(10, 0.0, 0.0), kDt, kFast);
  a.observe(sample(12, 5.0, 2.0), kDt, kFast);
  EXPECT_EQ(a.step_along_peak_V(), 0.0);
  EXPECT_EQ(a.above_peak_V(), 2.0);
  a.observe(sample(13, 1.0, -3.0), kDt, kFast);  // fast down (4 V), the servo down 5 V: along
  EXPECT_NEAR(a.step_along_peak_V(), 5.0, 1e-12);
  EXPECT_EQ(a.below_peak_V(), 3.0);
  // Half a memory later the peaks are e^-1/2 of themselves.
  const auto ticks = static_cast<std::int64_t>(std::lround(0.5 * ServoActivity::kMemory_s / kDt));
  for (std::int64_t k = 14; k < 14 + ticks; ++k) a.observe(sample(k, 1.0, 0.0), kDt, kFast);
  EXPECT_NEAR(a.below_peak_V(), 3.0 * std::exp(-0.5), 1e-3);
  // Fast down, the servo up: against the feedforward, nothing taken.
  a.reset();
  a.observe(sample(0, 0.0, 0.0), kDt, kFast);
  a.observe(sample(1, -3.0, 0.5), kDt, kFast);
  EXPECT_EQ(a.step_along_peak_V(), 0.0);
  // The peaks decay per tick, across a gap too: 100 ticks missing take 100 ticks' decay.
  a.reset();
  a.observe(sample(0, 0.0, 2.0), kDt, kFast);
  a.observe(sample(101, 0.0, 0.0), kDt, kFast);
  EXPECT_NEAR(a.above_peak_V(), 2.0 * std::exp(-101 * kDt / ServoActivity::kMemory_s), 1e-12);
  // The bridge's safe state (u_ff 0, u its ramp to the safe voltage) is not the servo's.
  a.reset();
  CompensatorInput safe = sample(0, 0.0, 60.0);
  safe.safe_state = true;
  a.observe(safe, kDt, kFast);
  EXPECT_EQ(a.above_peak_V(), 0.0);
  // Without a feedforward known, nothing is learned of the servo.
  a.reset();
  a.observe({1, 5.0, 0.0, std::numeric_limits<double>::quiet_NaN()}, kDt, kFast);
  EXPECT_EQ(a.above_peak_V(), 0.0);
}

}  // namespace
}  // namespace hystloop
