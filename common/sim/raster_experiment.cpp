#include "sim/raster_experiment.hpp"

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

RasterRun run_raster(const TrackingExperiment& e, const IdentifiedModels& models, const RasterOptions& o) {
  ScanOptions per_axis = o.loop;
  per_axis.learning = o.learning;
  const LoopSimulationConfig one = scan_loop_config(e, models, per_axis);

  MultiAxisLoopConfig c;
  c.stage = flexure_stage(o.axes, o.coupling);
  for (std::size_t i = 0; i < static_cast<std::size_t>(o.axes); ++i) {
    const std::uint64_t seed = c.stage.axis[i].seed;
    c.stage.axis[i] = one.stage;
    c.stage.axis[i].seed = seed;  // each sensor its own noise
    c.limits[i] = one.limits;
    c.compensator[i] = one.compensator;
    c.servo[i] = one.servo;
  }
  c.block_ticks = one.block_ticks;
  MultiAxisLoopSimulation sim(c);

  RasterRun run;
  RasterSpec& r = run.raster;
  r.fast_axis = 0;
  r.slow_axis = 1;
  r.width_m = o.width_m;
  r.height_m = o.height_m;
  r.lines = o.lines;
  r.line_rate_hz = o.line_rate_hz;
  r.slow_mode = o.slow_mode;
  // The corners the compensator chooses for a line: two periods of the stage's resonance, what
  // neither the stage's model nor the servo knows well (Compensator::choose_corner).
  const StageModel& stage = c.compensator[0].stage;
  r.corner_s = stage.has_dynamics() ? 2.0 * 2.0 * std::numbers::pi / stage.second_order.natural_frequency() : 1e-3;
  // r.centre_m stays 0 m: the middle of the voltage range, as the one-axis scans.
  const double blend_s = 0.2;
  r.start_s = 0.5;  // after the approach, which starts after the plan's horizon (50 ms) from now
  r.settle_s = 0.05;
  sim.run(0.05);  // the first samples: each plan knows where its axis is
  try {
    sim.take_raster(r, o.decouple ? c.stage.coupling : AxisCoupling::identity(o.axes), blend_s);
  } catch (const ParameterError& err) {
    run.refused = true;
    run.reason = err.what();
    return run;
  }
  const double lines_end_s = r.start_s + r.lines / r.line_rate_hz;
  std::array<double, kScanAxes> sum_sq{}, sum_sq_meas{};
  sim.run(raster_duration_s(r) + r.start_s - sim.now_s(), [&](const MultiAxisTick& tick) {
    for (int i = 0; i < o.axes; ++i) {
      if (tick.flags[static_cast<std::size_t>(i)] & (sample_flags::kSaturated | sample_flags::kSlewLimited))
        ++run.clamped_ticks;
    }
    if (tick.t_s < r.start_s || tick.t_s >= lines_end_s) return;
    const AxisPositions want = evaluate(r, tick.t_s);
    run.t_s.push_back(tick.t_s);
    for (std::size_t i = 0; i < static_cast<std::size_t>(o.axes); ++i) {
      const double err = want[i] - tick.y_true_m[i];
      const double meas = want[i] - tick.y_m[i];
      run.error_m[i].push_back(err);
      sum_sq[i] += err * err;
      sum_sq_meas[i] += meas * meas;
      run.stats[i].max_abs_true_m = std::max(run.stats[i].max_abs_true_m, std::abs(err));
    }
  });
  for (std::size_t i = 0; i < static_cast<std::size_t>(o.axes); ++i) {
    TrackingStats& s = run.stats[i];
    s.n = run.t_s.size();
    if (s.n == 0) continue;
    s.rms_true_m = std::sqrt(sum_sq[i] / static_cast<double>(s.n));
    s.rms_measured_m = std::sqrt(sum_sq_meas[i] / static_cast<double>(s.n));
  }
  run.stage_trips = sim.bridge().stage_trips();
  return run;
}

}  // namespace hystloop
