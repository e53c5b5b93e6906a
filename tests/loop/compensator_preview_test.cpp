// A linear stage of any order with a delay, inverted with the plan's preview
// (FeedforwardPlanner::preview_tick, models/preview_inverse.hpp): the compensator's commands,
// applied to the series model it inverts (the hysteresis, then the stage), put the stage where
// the reference is at every tick end; a new trajectory is still taken while one runs, learning
// still learns, and a dry run still refuses what leaves the actuator's limits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include "compensator_rig.hpp"
#include "loop/compensator.hpp"
#include "models/linear.hpp"
#include "models/linear_stage.hpp"

namespace hystloop {
namespace {

using testing::kDt;

// The stages the product meets: lightly damped modes with a fractional delay (the sampling zero
// pushed outside the unit circle), one without delay (its sampling zero at -0.98), and a
// non-minimum-phase zero.
LinearStageSpec two_modes(double delay_s) {
  return LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s);
}
LinearStageSpec non_minimum_phase() {
  return LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-300.0, 950.0}, {-2000.0, 0.0}}, 0.0);
}

struct Loop {
  Compensator compensator;
  LinearModel hysteresis;  // the plant's: the compensator's linear model (its inverse is exact)
  LinearStageSimulator stage;
  std::vector<double> y, y_ref;
  std::vector<CommandTick> plan = std::vector<CommandTick>(4096);
  std::vector<double> u_by_tick = std::vector<double>(200'000, std::numeric_limits<double>::quiet_NaN());
  std::int64_t k = 0;

  Loop(const CompensatorConfig& config, const LinearStageSpec& plant)
      : compensator(config), hysteresis(config.models.linear), stage(discretise(plant, kDt)) {
    stage.reset(0.0);
  }

  // The ideal bridge: each tick applies what was planned for it (the last voltage when none was),
  // and the samples reach the compensator in blocks of ten.
  void run(std::int64_t ticks) {
    double u = 0.0;
    for (std::int64_t n = 0; n < ticks; ++n, ++k) {
      if (!std::isnan(u_by_tick[static_cast<std::size_t>(k)])) u = u_by_tick[static_cast<std::size_t>(k)];
      const double yk = stage.step(hysteresis.forward(u));
      y.push_back(yk);
      y_ref.push_back(reference_of(k));
      compensator.observe({k, u, yk, u});
      if ((k + 1) % 10 == 0 || k == 0) {
        while (const std::size_t m = compensator.plan(plan)) {
          for (std::size_t i = 0; i < m; ++i) {
            u_by_tick[static_cast<std::size_t>(plan[i].seq)] = plan[i].u_ff_V;
            ref_by_tick[plan[i].seq] = plan[i].y_ref_m;
          }
        }
      }
    }
  }
  double reference_of(std::int64_t tick) const {
    const auto it = ref_by_tick.find(tick);
    return it == ref_by_tick.end() ? std::numeric_limits<double>::quiet_NaN() : it->second;
  }
  // max |y - y_ref| over [from, to) relative to max |y_ref| there.
  double relative_error(std::int64_t from, std::int64_t to) const {
    double e = 0.0, r = 0.0;
    for (std::int64_t i = from; i < to; ++i) {
      e = std::max(e, std::abs(y[static_cast<std::size_t>(i)] - y_ref[static_cast<std::size_t>(i)]));
      r = std::max(r, std::abs(y_ref[static_cast<std::size_t>(i)]));
    }
    return e / r;
  }
  std::map<std::int64_t, double> ref_by_tick;
};

CompensatorConfig config_for(const LinearStageSpec& stage) {
  CompensatorConfig c = testing::compensator_config(FeedforwardMode::kLinear, 500);
  c.stage.kind = StageModel::Kind::kLinear;
  c.stage.linear = stage;
  c.learning.enabled = false;
  return c;
}

TrajectorySpec sine(double amplitude_m, double frequency_hz) {
  TrajectorySpec t;
  t.shape = TrajectoryShape::kSine;
  t.amplitude_m = amplitude_m;
  t.frequency_hz = frequency_hz;
  t.blend_s = 0.05;
  return t;
}

TEST(CompensatorPreview, TheSeriesModelReproducesTheReferenceAtEveryTickEnd) {
  for (const LinearStageSpec& stage : {two_modes(1.5e-4), two_modes(0.0), two_modes(3.2e-4), non_minimum_phase()}) {
    Loop loop(config_for(stage), stage);
    loop.run(1);
    ASSERT_TRUE(loop.compensator.set_trajectory(sine(1e-6, 50.0), std::numeric_limits<double>::quiet_NaN()));
    loop.run(3000);
    // Through the approach and two periods of the line: the model inverted exactly, so the stage is
    // where the reference is, to rounding.
    EXPECT_LT(loop.relative_error(600, 3000), 1e-9)
        << "stage of order " << stage.order() << ", delay " << stage.delay_s;
    EXPECT_EQ(loop.compensator.counters().nonfinite_outputs, 0U);
  }
}

TEST(CompensatorPreview, ANewTrajectoryIsTakenWhileOneRuns) {
  const LinearStageSpec stage = two_modes(1.5e-4);
  Loop loop(config_for(stage), stage);
  loop.run(1);
  loop.compensator.set_trajectory(sine(1e-6, 20.0), std::numeric_limits<double>::quiet_NaN());
  loop.run(2000);
  loop.compensator.set_trajectory(sine(0.5e-6, 40.0), std::numeric_limits<double>::quiet_NaN());
  loop.run(3000);
  EXPECT_LT(loop.relative_error(600, 5000), 1e-9);
  EXPECT_DOUBLE_EQ(loop.compensator.trajectory().frequency_hz, 40.0);
}

TEST(CompensatorPreview, AReferenceBeyondTheActuatorIsRefusedByTheDryRun) {
  const LinearStageSpec stage = two_modes(1.5e-4);
  CompensatorConfig c = config_for(stage);
  c.u_min_V = -250.0;
  c.u_max_V = 250.0;
  c.slew_V_per_s = 5e4;
  c.slew_fraction = CompensatorConfig{}.slew_fraction;
  Compensator compensator(c);
  compensator.observe({0, 0.0, 0.0, 0.0});
  // 3 um at 700 Hz: far beyond the slew limit through a resonance the inverse must undo.
  EXPECT_THROW(compensator.set_trajectory(sine(3e-6, 700.0), std::numeric_limits<double>::quiet_NaN()), ParameterError);
  EXPECT_EQ(compensator.counters().plan_refusals, 1U);
}

TEST(CompensatorPreview, AStageTheInverseCannotTakeIsRefusedNamingThePreview) {
  CompensatorConfig c = config_for(two_modes(1.5e-4));
  c.stage.preview_ticks = 1;  // shorter than its delay
  try {
    const Compensator refused(c);
    FAIL() << "a preview shorter than the delay was accepted";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "stage.preview_ticks");
  }
  c.stage.preview_ticks = 0;
  c.stage.order = BanningOrder::kStageThenHysteresis;
  EXPECT_THROW(const Compensator refused(c), ParameterError);
}

}  // namespace
}  // namespace hystloop
