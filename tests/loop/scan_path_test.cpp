#include "loop/scan_path.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using testing::refused_field;

constexpr double kPi = std::numbers::pi;
constexpr double kDt = 1e-4;      // the loop's tick [s]
constexpr double kGain = 6.4e-9;  // [m/V]: 1 um takes 156.25 V
constexpr std::size_t kX = 0, kY = 1, kZ = 2;

// 8 lines of 20 um at 100 lines/s, 10 um high, corners of 1 ms, around (1, -2, 0.5) um.
RasterSpec raster(SlowMode mode = SlowMode::kSteps) {
  return {.fast_axis = 0,
          .slow_axis = 1,
          .width_m = 20e-6,
          .height_m = 10e-6,
          .lines = 8,
          .line_rate_hz = 100.0,
          .corner_s = 1e-3,
          .centre_m = {1e-6, -2e-6, 0.5e-6},
          .slow_mode = mode,
          .settle_s = 0.02,
          .start_s = 0.5};
}

// 64 lines of 2 um around 0, 2 um high: steps of 32 nm (8 lines would step 0.29 um within a 1 ms
// corner, 8.9e4 V/s).
RasterSpec two_micron_raster() {
  RasterSpec s = raster();
  s.centre_m = {};
  s.width_m = 2e-6;
  s.height_m = 2e-6;
  s.lines = 64;
  return s;
}

double line_start_s(const RasterSpec& s, int k) { return s.start_s + k / s.line_rate_hz; }

// Samples on line k's straight part, ends included.
template <class F>
void on_straight_of(const RasterSpec& s, int k, F&& f) {
  const double from = line_start_s(s, k) + 0.5 * s.corner_s, to = line_start_s(s, k + 1) - 0.5 * s.corner_s;
  for (int i = 0; i <= 20; ++i) f(from + (to - from) * i / 20.0);
}

TEST(ScanPath, RasterStepsGeometry) {
  const RasterSpec s = raster();
  s.validate();
  EXPECT_NEAR(raster_duration_s(s), 8 / 100.0 + 0.02, 1e-15);
  const double spacing_m = 10e-6 / 7;
  for (int k = 0; k < s.lines; ++k) {
    const double dir = k % 2 == 0 ? 1.0 : -1.0;
    // Each line runs from one end of the fast travel to the other, ends at rest in a corner's centre.
    EXPECT_NEAR(evaluate(s, line_start_s(s, k))[kX], 1e-6 - dir * 10e-6, 1e-15) << k;
    EXPECT_NEAR(evaluate(s, line_start_s(s, k + 1))[kX], 1e-6 + dir * 10e-6, 1e-15) << k;
    EXPECT_NEAR(evaluate(s, line_start_s(s, k) + 0.005)[kX], 1e-6, 1e-15) << k;  // half way: the centre
    on_straight_of(s, k, [&](double t) {
      const AxisPositions y = evaluate(s, t);
      EXPECT_NEAR(y[kY], -2e-6 - 5e-6 + k * spacing_m, 1e-18) << k << " " << t;
      EXPECT_EQ(y[kZ], 0.5e-6);  // not in the raster: holds its centre
    });
  }
  // Before the start: at line 0's start; from the end of the lines on, through the settle and
  // after: at the last line's end (8 lines: back at the low end, at the top line).
  for (double t : {0.0, 0.49, 0.5}) {
    const AxisPositions y = evaluate(s, t);
    EXPECT_NEAR(y[kX], 1e-6 - 10e-6, 1e-15) << t;
    EXPECT_NEAR(y[kY], -7e-6, 1e-18) << t;
  }
  for (double t : {0.58, 0.59, 0.6, 7.0}) {
    const AxisPositions y = evaluate(s, t);
    EXPECT_NEAR(y[kX], 1e-6 - 10e-6, 1e-15) << t;
    EXPECT_NEAR(y[kY], 3e-6, 1e-18) << t;
  }
  RasterSpec odd = s;
  odd.lines = 7;
  EXPECT_NEAR(evaluate(odd, 10.0)[kX], 1e-6 + 10e-6, 1e-15);  // an odd count ends at the high end
}

TEST(ScanPath, RasterRampIsMonotoneWithOneSlopeOnEveryLine) {
  for (double corner_s : {1e-3, 0.0}) {
    RasterSpec s = raster(SlowMode::kRamp);
    s.corner_s = corner_s;
    s.validate();
    const double lines_s = 0.08;
    const double slope = 10e-6 / (lines_s - 0.5 * corner_s);  // [m/s]
    double prev = evaluate(s, 0.4)[kY];
    EXPECT_NEAR(prev, -7e-6, 1e-18);
    for (int n = 0; n <= 1500; ++n) {
      const double y = evaluate(s, 0.49 + n * kDt)[kY];
      EXPECT_GE(y, prev) << n;
      prev = y;
    }
    EXPECT_NEAR(evaluate(s, 0.5 + lines_s)[kY], 3e-6, 1e-18);
    for (int k = 0; k < s.lines; ++k) {
      on_straight_of(s, k, [&](double t) {
        const double from = 0.5 + 0.5 * corner_s;
        if (t < from) return;
        EXPECT_NEAR(evaluate(s, t)[kY] - evaluate(s, from)[kY], slope * (t - from), 1e-17) << t;
      });
    }
  }
}

// Consecutive ticks differ by at most the peak velocity times the tick, and their second
// difference by the peak acceleration times the tick squared, on every axis: no steps, and the
// peaks of raster_peaks are not too low. The fast axis's largest step is its slope's: they are not
// vacuous either.
TEST(ScanPath, RasterIsContinuousWithinItsPeaks) {
  for (SlowMode mode : {SlowMode::kSteps, SlowMode::kRamp}) {
    const RasterSpec s = raster(mode);
    const auto peaks = raster_peaks(s);
    std::array<double, kScanAxes> max_step{}, max_bend{};
    AxisPositions before = evaluate(s, 0.49 - kDt), prev = evaluate(s, 0.49);
    for (int n = 1; n <= 1200; ++n) {
      const AxisPositions y = evaluate(s, 0.49 + n * kDt);
      for (std::size_t i = 0; i < kScanAxes; ++i) {
        max_step[i] = std::max(max_step[i], std::abs(y[i] - prev[i]));
        max_bend[i] = std::max(max_bend[i], std::abs(y[i] - 2 * prev[i] + before[i]));
      }
      before = prev;
      prev = y;
    }
    for (std::size_t i = 0; i < kScanAxes; ++i) {
      EXPECT_LE(max_step[i], peaks[i].derivatives.velocity_m_per_s * kDt * (1 + 1e-9) + 1e-20) << i;
      EXPECT_LE(max_bend[i], peaks[i].derivatives.acceleration_m_per_s2 * kDt * kDt * (1 + 1e-6) + 1e-20) << i;
    }
    EXPECT_GT(max_step[kX], 0.99 * peaks[kX].derivatives.velocity_m_per_s * kDt);
    EXPECT_EQ(max_step[kZ], 0.0);
    EXPECT_EQ(peaks[kZ].min_m, 0.5e-6);
    EXPECT_EQ(peaks[kZ].max_m, 0.5e-6);
  }
  const auto steps = raster_peaks(raster());
  const double spacing_m = 10e-6 / 7;
  EXPECT_NEAR(steps[kY].derivatives.velocity_m_per_s, 2 * spacing_m / 1e-3, 1e-15);
  EXPECT_NEAR(steps[kY].min_m, -7e-6, 1e-18);
  EXPECT_NEAR(steps[kX].max_m, 11e-6, 1e-18);
  EXPECT_EQ(steps[kX].derivatives.velocity_m_per_s,
            peak_derivatives(raster_fast_trajectory(raster())).velocity_m_per_s);
}

TEST(ScanPath, RasterPointAgreesWithThePositions) {
  const RasterSpec s = raster();
  const double spacing_m = 10e-6 / 7;
  int straight = 0, turning = 0;
  for (int n = 0; n <= 1000; ++n) {
    const double t = 0.5 + n * kDt + 0.3e-4;  // off the grid of line boundaries
    const RasterPoint p = raster_point(s, t);
    const AxisPositions y = evaluate(s, t);
    if (t - 0.5 >= 0.08) {  // the settle
      EXPECT_FALSE(p.on_straight) << t;
      EXPECT_EQ(p.line, 7);
      EXPECT_EQ(p.along, 1.0);
      continue;
    }
    EXPECT_EQ(p.line, static_cast<int>(std::floor((t - 0.5) * 100.0))) << t;
    EXPECT_EQ(p.direction, p.line % 2 == 0 ? 1 : -1) << t;
    const double from_low = p.direction > 0 ? p.along : 1.0 - p.along;
    EXPECT_NEAR(y[kX], 1e-6 - 10e-6 + from_low * 20e-6, 1e-15) << t;
    const double local_s = t - line_start_s(s, p.line);
    EXPECT_EQ(p.on_straight, local_s >= 0.5e-3 && local_s <= 10e-3 - 0.5e-3) << t;
    if (p.on_straight) {
      ++straight;
      EXPECT_NEAR(y[kY], -7e-6 + p.line * spacing_m, 1e-18) << t;
      EXPECT_GT((evaluate(s, t + 1e-6)[kX] - y[kX]) * p.direction, 0.0) << t;  // moving as it says
    } else {
      ++turning;
    }
  }
  EXPECT_GT(straight, 700);
  EXPECT_GT(turning, 50);
  const RasterPoint before = raster_point(s, 0.2);
  EXPECT_EQ(before.line, 0);
  EXPECT_EQ(before.along, 0.0);
  EXPECT_EQ(before.direction, 1);
  EXPECT_FALSE(before.on_straight);
}

TEST(ScanPath, EvaluationAllocatesNothing) {
  const RasterSpec r = raster();
  LissajousSpec l;
  l.amplitude_m = {1e-6, 1e-6, 0.0};
  l.frequency_hz = {100.0, 101.0, 0.0};
  double sum = 0.0;
  hystloop::testing::AllocationCounter counter;
  for (int n = 0; n < 2000; ++n) {
    sum += evaluate(r, 0.5 + n * kDt)[kX] + raster_point(r, 0.5 + n * kDt).along + evaluate(l, n * kDt)[kY];
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

// evaluate() and raster_point() run on specs nobody validated (they are noexcept, for the tick):
// such a spec gives a held position and line 0, never a NaN line number converted to int (the
// sanitizer build would report that) or an index past the axes.
TEST(ScanPath, UnvalidatedSpecsEvaluateToTheStartWithoutUndefinedBehaviour) {
  for (const double rate : {std::numeric_limits<double>::infinity(), std::nan(""), 0.0, -1.0}) {
    RasterSpec s = raster();
    s.line_rate_hz = rate;
    EXPECT_EQ(raster_point(s, 1.0).line, 0) << rate;
    EXPECT_FALSE(raster_point(s, 1.0).on_straight) << rate;
  }
  RasterSpec s = raster();
  s.lines = RasterSpec::kMaxLines + 1;
  EXPECT_EQ(raster_point(s, 1.0).line, 0);
  s = raster();
  s.fast_axis = 7;
  EXPECT_FALSE(raster_point(s, 1.0).on_straight);
}

TEST(ScanPath, RasterValidationNamesTheField) {
  auto refused = [](auto change) {
    RasterSpec s = raster();
    change(s);
    return refused_field([&] { s.validate(); });
  };
  EXPECT_EQ(refused([](RasterSpec& s) { s.slow_axis = s.fast_axis; }), "raster.slow_axis");
  EXPECT_EQ(refused([](RasterSpec& s) { s.fast_axis = 3; }), "raster.fast_axis");
  EXPECT_EQ(refused([](RasterSpec& s) { s.slow_axis = -1; }), "raster.slow_axis");
  EXPECT_EQ(refused([](RasterSpec& s) { s.lines = 1; }), "raster.lines");
  EXPECT_EQ(refused([](RasterSpec& s) { s.lines = 4097; }), "raster.lines");
  EXPECT_EQ(refused([](RasterSpec& s) { s.width_m = std::nan(""); }), "raster.width_m");
  EXPECT_EQ(refused([](RasterSpec& s) { s.width_m = -1e-6; }), "raster.width_m");
  EXPECT_EQ(refused([](RasterSpec& s) { s.height_m = -1e-6; }), "raster.height_m");
  EXPECT_EQ(refused([](RasterSpec& s) { s.height_m = std::numeric_limits<double>::infinity(); }), "raster.height_m");
  EXPECT_EQ(refused([](RasterSpec& s) { s.line_rate_hz = 0.0; }), "raster.line_rate_hz");
  EXPECT_EQ(refused([](RasterSpec& s) { s.corner_s = 0.01; }), "raster.corner_s");  // a whole line
  EXPECT_EQ(refused([](RasterSpec& s) { s.corner_s = 0.0; }), "raster.corner_s");   // steps need a corner
  EXPECT_EQ(refused([](RasterSpec& s) { s.centre_m[2] = std::nan(""); }), "raster.centre_m");
  EXPECT_EQ(refused([](RasterSpec& s) { s.settle_s = -1.0; }), "raster.settle_s");
  EXPECT_EQ(refused([](RasterSpec& s) { s.slow_mode = static_cast<SlowMode>(7); }), "raster.slow_mode");
  RasterSpec ramp = raster(SlowMode::kRamp);
  ramp.corner_s = 0.0;
  EXPECT_NO_THROW(ramp.validate());
  // The message carries the unit.
  RasterSpec s = raster();
  s.height_m = -1e-6;
  try {
    s.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(std::string(e.what()), "raster.height_m: must be >= 0 m (got -1e-06 m)");
  }
}

LissajousSpec lissajous() {
  LissajousSpec s;
  s.amplitude_m = {2e-6, 3e-6, 0.0};
  s.frequency_hz = {100.0, 101.0, 0.0};
  s.phase_rad = {0.0, 0.5 * kPi, 0.0};
  s.centre_m = {1e-6, 0.0, 0.5e-6};
  s.duration_s = 1.0;
  s.start_s = 2.0;
  return s;
}

TEST(ScanPath, LissajousAtKnownTimes) {
  const LissajousSpec s = lissajous();
  s.validate();
  const AxisPositions a = evaluate(s, 2.0025);  // a quarter of x's period
  EXPECT_NEAR(a[kX], 3e-6, 1e-18);
  EXPECT_NEAR(a[kY], 3e-6 * std::cos(2 * kPi * 101.0 * 0.0025), 1e-18);
  EXPECT_EQ(a[kZ], 0.5e-6);
  const AxisPositions b = evaluate(s, 2.5);  // x: 50 whole periods; y: 50.5, a half turn from its start
  EXPECT_NEAR(b[kX], 1e-6, 1e-17);
  EXPECT_NEAR(b[kY], -3e-6, 1e-17);
  // Held at tau = 0 before the start and at duration_s after it.
  EXPECT_NEAR(evaluate(s, 1.0)[kX], 1e-6, 1e-18);
  EXPECT_NEAR(evaluate(s, 1.0)[kY], 3e-6, 1e-18);
  EXPECT_NEAR(evaluate(s, 9.0)[kY], 3e-6, 1e-16);
  EXPECT_EQ(evaluate(s, 9.0)[kX], evaluate(s, 3.0)[kX]);
  const auto peaks = lissajous_peaks(s);
  EXPECT_NEAR(peaks[kY].derivatives.velocity_m_per_s, 2 * kPi * 101.0 * 3e-6, 1e-15);
  EXPECT_NEAR(peaks[kX].max_m, 3e-6, 1e-18);
  EXPECT_EQ(peaks[kZ].derivatives.velocity_m_per_s, 0.0);
}

TEST(ScanPath, LissajousValidationNamesTheField) {
  auto refused = [](auto change) {
    LissajousSpec s = lissajous();
    change(s);
    return refused_field([&] { s.validate(); });
  };
  EXPECT_EQ(refused([](LissajousSpec& s) { s.frequency_hz[1] = 0.0; }), "lissajous.frequency_hz");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.amplitude_m[0] = -1e-6; }), "lissajous.amplitude_m");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.amplitude_m = {}; }), "lissajous.amplitude_m");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.phase_rad[0] = std::numeric_limits<double>::infinity(); }),
            "lissajous.phase_rad");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.centre_m[2] = std::nan(""); }), "lissajous.centre_m");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.duration_s = 0.0; }), "lissajous.duration_s");
  EXPECT_EQ(refused([](LissajousSpec& s) { s.start_s = std::nan(""); }), "lissajous.start_s");
}

std::array<AxisActuator, 3> static_gains() {
  AxisActuator a;
  a.plant = {kGain, std::nullopt};
  return {a, a, a};  // +-250 V, 5e4 V/s each
}

TEST(ScanPath, FastAxisOverItsSlewLimitIsRefusedByName) {
  // 2 um lines (+-156 V): the fast slope is width * line rate, a little more with the corners of
  // 1 ms: 2e-6 m / (10 ms - 1 ms + 2 ms / pi) = 2.08e-4 m/s, 3.2e4 V/s at 100 lines/s; 6.7e4 V/s at 200.
  RasterSpec s = two_micron_raster();
  const auto actuators = static_gains();
  const ScanFeasibility fine = check_raster_feasible(s, actuators);
  EXPECT_TRUE(fine.ok()) << fine.reason;
  EXPECT_EQ(fine.axis, -1);
  EXPECT_EQ(fine.reason, "");
  // The fast axis's need is feasibility.hpp's triangle, exactly.
  const VoltageNeed tri = voltage_need(actuators[0].plant, raster_fast_trajectory(s));
  EXPECT_EQ(fine.needs[kX].rate_V_per_s, tri.rate_V_per_s);
  EXPECT_NEAR(fine.needs[kX].rate_V_per_s, 2e-6 / (9e-3 + 2e-3 / kPi) / kGain, 1e-6);

  s.line_rate_hz = 200.0;
  const ScanFeasibility fast = check_raster_feasible(s, actuators);
  EXPECT_FALSE(fast.ok());
  EXPECT_EQ(fast.axis, 0);
  EXPECT_EQ(fast.limit, Limit::kSlew);
  EXPECT_EQ(fast.reason, "x (fast axis) exceeds its slew limit: needs 67398.2 V/s, 50000 V/s usable");

  s.fast_axis = 1;  // the same lines along y
  s.slow_axis = 0;
  const ScanFeasibility along_y = check_raster_feasible(s, actuators);
  EXPECT_EQ(along_y.axis, 1);
  EXPECT_EQ(along_y.reason.rfind("y (fast axis) exceeds its slew limit", 0), 0u) << along_y.reason;
}

TEST(ScanPath, SlowAxisOutOfRangeAndMissingActuatorsAreRefused) {
  RasterSpec s = raster();
  s.centre_m = {};
  s.width_m = 2e-6;
  s.height_m = 4e-6;  // +-2 um: +-312.5 V
  const auto actuators = static_gains();
  const ScanFeasibility tall = check_raster_feasible(s, actuators);
  EXPECT_EQ(tall.axis, 1);
  EXPECT_EQ(tall.limit, Limit::kRange);
  EXPECT_EQ(tall.reason, "y (slow axis) exceeds its range limit: needs [-312.5, 312.5] V, [-250, 250] V usable");
  s.height_m = 2e-6;
  // Stepping is fast: 8 lines step 2/7 um within each 1 ms corner, at up to 2 h / c = 5.7e-4 m/s,
  // faster than the fast axis itself.
  const ScanFeasibility steep = check_raster_feasible(s, actuators);
  EXPECT_EQ(steep.axis, 1);
  EXPECT_EQ(steep.limit, Limit::kSlew);
  EXPECT_EQ(steep.reason, "y (slow axis) exceeds its slew limit: needs 89285.7 V/s, 50000 V/s usable");
  s.lines = 64;
  EXPECT_TRUE(check_raster_feasible(s, actuators).ok());
  s.centre_m[2] = 2e-6;  // z is not scanned, but holding 2 um still takes 312.5 V
  const ScanFeasibility held = check_raster_feasible(s, actuators);
  EXPECT_EQ(held.axis, 2);
  EXPECT_EQ(held.reason.rfind("z (holding its centre) exceeds its range limit", 0), 0u) << held.reason;
  // A path axis with no actuator is a configuration error, as is a broken actuator.
  EXPECT_EQ(refused_field([&] { check_raster_feasible(s, std::span(actuators).first(1)); }), "raster.slow_axis");
  auto broken = actuators;
  broken[1].limits.slew_V_per_s = -1.0;
  EXPECT_EQ(refused_field([&] { check_raster_feasible(s, broken); }), "y.limits.slew_V_per_s");
}

TEST(ScanPath, SlowAxisBoundWithTheStageIsAboveItsOwnRate) {
  // With Banning's stage the slow axis's bound adds the inverse's derivative terms to the static
  // rate v / g; for this raster's gentle steps they are small but present.
  RasterSpec s = two_micron_raster();
  std::array<AxisActuator, 2> actuators{};
  for (auto& a : actuators) a.plant = {kGain, SecondOrderStageParams{}};
  const ScanFeasibility v = check_raster_feasible(s, actuators);
  EXPECT_TRUE(v.ok()) << v.reason;
  const AxisPeaks peaks = raster_peaks(s)[kY];
  const ShapePeaks& d = peaks.derivatives;
  EXPECT_GT(v.needs[kY].rate_V_per_s, d.velocity_m_per_s / kGain);
  EXPECT_GT(v.needs[kY].u_max_V, 1e-6 / kGain);
  // The bound term by term: u = (y + (c/k) y' + y''/k) / g with each derivative at its peak.
  const SecondOrderStageParams stage;
  const double margin_m = stage.c / stage.k * d.velocity_m_per_s + d.acceleration_m_per_s2 / stage.k;
  EXPECT_DOUBLE_EQ(v.needs[kY].u_max_V, (peaks.max_m + margin_m) / kGain);
  EXPECT_DOUBLE_EQ(v.needs[kY].u_min_V, (peaks.min_m - margin_m) / kGain);
  EXPECT_DOUBLE_EQ(
      v.needs[kY].rate_V_per_s,
      (d.velocity_m_per_s + stage.c / stage.k * d.acceleration_m_per_s2 + d.jerk_m_per_s3 / stage.k) / kGain);
}

TEST(ScanPath, LissajousAxisOverItsSlewLimitIsRefusedByName) {
  LissajousSpec s = lissajous();
  s.centre_m = {};
  s.amplitude_m = {1e-6, 1e-6, 0.0};
  s.frequency_hz = {30.0, 31.0, 0.0};  // 2 pi 31 1e-6 / 6.4e-9 = 3.0e4 V/s
  const auto actuators = static_gains();
  EXPECT_TRUE(check_lissajous_feasible(s, actuators).ok());
  s.frequency_hz[1] = 60.0;  // 5.9e4 V/s
  const ScanFeasibility v = check_lissajous_feasible(s, actuators);
  EXPECT_EQ(v.axis, 1);
  EXPECT_EQ(v.limit, Limit::kSlew);
  EXPECT_EQ(v.reason.rfind("y exceeds its slew limit", 0), 0u) << v.reason;
  EXPECT_EQ(v.needs[kY].rate_V_per_s, sine_need(actuators[1].plant, 1e-6, 60.0, 0.0).rate_V_per_s);
}

}  // namespace
}  // namespace hystloop

namespace hystloop {
namespace {

// C with x moving y by 3 % and z by 1 %, y moving x by -2 %.
AxisCoupling coupled() {
  AxisMatrix c = AxisMatrix::Identity();
  c(1, 0) = 0.03;
  c(2, 0) = 0.01;
  c(0, 1) = -0.02;
  return AxisCoupling(3, c);
}

TEST(ScanShare, AnIdentityRowIsThePathsOwnAxisBitForBit) {
  const RasterSpec s = raster();
  for (int axis = 0; axis < 3; ++axis) {
    AxisVector row = AxisVector::Zero();
    row[axis] = 1.0;
    const ScanShare share(s, axis, row);
    for (double t = 0.4; t < 0.6; t += 3.7e-4) {
      const ScanShare::Point p = share.point(t);
      EXPECT_EQ(p.own_m, evaluate(s, t)[static_cast<std::size_t>(axis)]) << t;
      EXPECT_EQ(p.share_m, p.own_m) << t;
    }
  }
}

TEST(ScanShare, TheSharesOfTheInverseCouplingAddUpToThePathThroughTheStage) {
  const AxisCoupling c = coupled();
  const RasterSpec s = raster(SlowMode::kRamp);
  std::vector<ScanShare> shares;
  shares.reserve(3);
  for (int axis = 0; axis < 3; ++axis) shares.emplace_back(s, axis, c.inverse_matrix().row(axis).transpose());
  for (double t = 0.45; t < 0.6; t += 1.3e-4) {
    AxisVector w;
    for (int axis = 0; axis < 3; ++axis) w[axis] = shares[static_cast<std::size_t>(axis)].at(t);
    const AxisVector y = c.couple(w);  // what the stage's sensors read when each axis reaches its share
    const AxisPositions r = evaluate(s, t);
    for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(y[axis], r[static_cast<std::size_t>(axis)], 1e-20) << t;
  }
}

TEST(ScanShare, OnlyARastersFastAxisAloneIsPeriodicUpToSubNanometreEntries) {
  const RasterSpec s = raster();
  EXPECT_NE(ScanShare(s, 0, AxisVector(1.0, 0.0, 0.0)).periodic_part(), nullptr);
  EXPECT_EQ(ScanShare(s, 1, AxisVector(-0.03, 1.0, 0.0)).periodic_part(), nullptr);
  EXPECT_EQ(ScanShare(s, 0, AxisVector(1.0, 0.02, 0.0)).periodic_part(), nullptr);
  // An identified coupling's near-zero entries (5e-6 of y's 10 um, 1 + 1e-7 on the diagonal) move
  // the share by 0.05 nm: still the fast axis's line, which learning must follow; 2e-5 of y (0.2 nm)
  // is past the tolerance.
  EXPECT_NE(ScanShare(s, 0, AxisVector(1.0 + 1e-7, -5e-6, 0.0)).periodic_part(), nullptr);
  EXPECT_EQ(ScanShare(s, 0, AxisVector(1.0, -2e-5, 0.0)).periodic_part(), nullptr);
  const ScanShare x(s, 0, AxisVector(1.0, 0.0, 0.0));
  const TrajectorySpec* fast = x.periodic_part();
  ASSERT_NE(fast, nullptr);
  EXPECT_DOUBLE_EQ(fast->frequency_hz, 50.0);  // two lines per period at 100 lines/s
}

TEST(ScanShare, RefusesARowWithoutItsOwnAxisOrWithANonFiniteWeight) {
  const RasterSpec s = raster();
  EXPECT_EQ(refused_field([&] { ScanShare(s, 1, AxisVector(1.0, 0.0, 0.0)); }), "scan.row");
  EXPECT_EQ(refused_field([&] { ScanShare(s, 0, AxisVector(1.0, std::nan(""), 0.0)); }), "scan.row");
  EXPECT_EQ(refused_field([&] { ScanShare(s, 3, AxisVector(1.0, 0.0, 0.0)); }), "scan.axis");
  RasterSpec bad = s;
  bad.lines = 1;
  EXPECT_EQ(refused_field([&] { ScanShare(bad, 0, AxisVector(1.0, 0.0, 0.0)); }), "raster.lines");
}

TEST(ScanShare, EvaluatesWithoutAllocating) {
  const ScanShare share(raster(), 1, coupled().inverse_matrix().row(1).transpose());
  LissajousSpec l;
  l.amplitude_m = {1e-6, 2e-6, 0.0};
  l.frequency_hz = {50.0, 49.0, 1.0};
  const ScanShare figure(l, 0, coupled().inverse_matrix().row(0).transpose());
  double sum = 0.0;
  {
    const testing::AllocationCounter count;
    for (int n = 0; n < 1000; ++n) sum += share.at(0.5 + n * kDt) + figure.point(n * kDt).own_m;
    EXPECT_EQ(count.allocations(), 0u);
  }
  EXPECT_TRUE(std::isfinite(sum));
  // The figure's share is its row times the axes' sines.
  const AxisPositions r = evaluate(l, 0.0123);
  const AxisVector row = coupled().inverse_matrix().row(0).transpose();
  EXPECT_NEAR(figure.at(0.0123), row[0] * r[kX] + row[1] * r[kY] + row[2] * r[kZ], 1e-20);
}

}  // namespace
}  // namespace hystloop
