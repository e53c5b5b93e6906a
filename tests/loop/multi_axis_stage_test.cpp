// The simulated XY(Z) stage (common/loop/multi_axis_stage.hpp): one axis is the one-axis stage bit
// for bit; the coupling moves the other axes by C_ji times the moving axis's displacement, exactly;
// a sensor's noise stays on its own axis; refusals name the axis.
#include "loop/multi_axis_stage.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;  // [s], the loop's tick

double triangle_V(int k) {  // +-100 V at 5 Hz
  const double phase = std::fmod(5.0 * k * kDt, 1.0);
  return 100.0 * (phase < 0.5 ? 4.0 * phase - 1.0 : 3.0 - 4.0 * phase);
}

MultiAxisStageConfig quiet(MultiAxisStageConfig c) {
  for (auto& a : c.axis) a.noise_rms_m = 0.0;
  return c;
}

TEST(MultiAxisStage, OneAxisIsTheOneAxisStageBitForBit) {
  MultiAxisStageConfig config;  // one uncoupled axis, the default SimulatedStageConfig
  MultiAxisStage xy(config);
  SimulatedStage alone(SimulatedStageConfig{});
  ASSERT_EQ(xy.axes(), 1);
  for (int k = 0; k < 4000; ++k) {
    const std::array<double, 1> u{triangle_V(k)};
    std::array<double, 1> y{};
    xy.step(u, k * kDt, kDt, y);
    ASSERT_EQ(y[0], alone.step(u[0], k * kDt, kDt)) << "tick " << k;
  }
}

TEST(MultiAxisStage, CouplingMovesTheOtherAxesByItsEntries) {
  MultiAxisStage xyz(quiet(flexure_stage(3, 0.03)));
  double largest_x_m = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const std::array<double, 3> u{triangle_V(k), 0.0, 0.0};  // only x moves
    std::array<double, 3> y{};
    xyz.step(u, k * kDt, kDt, y);
    const double s_x = xyz.displacement_m(0);
    ASSERT_EQ(xyz.displacement_m(1), 0.0);
    ASSERT_EQ(y[0], s_x);
    ASSERT_DOUBLE_EQ(y[1], 0.03 * s_x) << "tick " << k;
    ASSERT_DOUBLE_EQ(y[2], 0.03 * s_x) << "tick " << k;
    ASSERT_EQ(xyz.true_position_m(1), y[1]);
    largest_x_m = std::max(largest_x_m, std::fabs(s_x));
  }
  EXPECT_GT(largest_x_m, 1e-6);  // the stage moved: the 3 % is ~30 nm, not rounding
}

TEST(MultiAxisStage, SensorNoiseStaysOnItsAxis) {
  MultiAxisStageConfig c = quiet(flexure_stage(2, 0.03));
  c.axis[0].noise_rms_m = 1e-9;
  MultiAxisStage xy(c);
  double sum_sq_x = 0.0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const std::array<double, 2> u{0.0, 0.0};
    std::array<double, 2> y{};
    xy.step(u, k * kDt, kDt, y);
    ASSERT_EQ(y[1], 0.0) << "x's sensor noise reached y's reading at tick " << k;
    sum_sq_x += y[0] * y[0];
  }
  EXPECT_NEAR(std::sqrt(sum_sq_x / n), 1e-9, 0.03e-9);  // 5 standard errors of the RMS at n = 2e4
}

TEST(MultiAxisStage, AxesDrawIndependentNoise) {
  MultiAxisStage xy(flexure_stage(2, 0.0));  // 1 nm per axis, seeds 1 and 2
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const std::array<double, 2> u{0.0, 0.0};
    std::array<double, 2> y{};
    xy.step(u, k * kDt, kDt, y);
    sxy += y[0] * y[1];
    sxx += y[0] * y[0];
    syy += y[1] * y[1];
  }
  EXPECT_LT(std::fabs(sxy / std::sqrt(sxx * syy)), 0.035);  // 5 / sqrt(2e4): independent draws
}

TEST(MultiAxisStage, RefusalsNameTheAxis) {
  MultiAxisStageConfig c = flexure_stage(2);
  c.axis[1].noise_rms_m = -1e-9;
  try {
    MultiAxisStage bad(c);
    FAIL() << "accepted a negative noise on y";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "axis[1].bridge.noise_rms_m");
  }
  c.axis[1].noise_rms_m = 1e-9;
  c.axis[1].seed = c.axis[0].seed;
  try {
    MultiAxisStage same_noise(c);
    FAIL() << "accepted two noisy sensors drawing the same noise";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "axis[1].seed");
  }
  c.axis[1].seed = c.axis[0].seed + 1;
  c.axis[2].noise_rms_m = -1.0;  // past n = 2: never used, not refused
  EXPECT_NO_THROW(MultiAxisStage ok(c));
}

TEST(MultiAxisStage, StepAllocatesNothing) {
  MultiAxisStage xyz(flexure_stage(3));
  std::array<double, 3> y{};
  testing::AllocationCounter allocations;
  for (int k = 0; k < 1000; ++k) {
    const std::array<double, 3> u{triangle_V(k), -triangle_V(k), 10.0};
    xyz.step(u, k * kDt, kDt, y);
  }
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(y[0]) && std::isfinite(y[1]) && std::isfinite(y[2]));
}

}  // namespace
}  // namespace hystloop
