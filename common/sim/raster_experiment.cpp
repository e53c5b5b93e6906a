#include "sim/raster_experiment.hpp"

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

namespace {

constexpr double kBlendS = 0.2;  // the approach to the path's start
// After the approach, which starts after the plan's horizon (50 ms) from the first samples.
constexpr double kStartS = 0.5;

// Per axis the one-axis scan loop, on a flexure stage coupled by o.coupling.
MultiAxisLoopConfig path_loop_config(const TrackingExperiment& e, const IdentifiedModels& models,
                                     const PathLoopOptions& o) {
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
  return c;
}

// Takes the path on every axis and runs it through `end_s`, measuring r - y over [start_s, end_s).
template <class Path>
void run_path(MultiAxisLoopSimulation& sim, const Path& path, const AxisCoupling& decoupling, double start_s,
              double end_s, double run_to_s, PathRun& run) {
  sim.run(0.05);  // the first samples: each plan knows where its axis is
  try {
    sim.take_path(path, decoupling, kBlendS);
  } catch (const ParameterError& err) {
    run.refused = true;
    run.reason = err.what();
    return;
  }
  const auto axes = static_cast<std::size_t>(sim.axes());
  std::array<double, kScanAxes> sum_sq{}, sum_sq_meas{};
  sim.run(run_to_s - sim.now_s(), [&](const MultiAxisTick& tick) {
    for (std::size_t i = 0; i < axes; ++i) {
      if (tick.flags[i] & (sample_flags::kSaturated | sample_flags::kSlewLimited)) ++run.clamped_ticks;
    }
    if (tick.t_s < start_s || tick.t_s >= end_s) return;
    const AxisPositions want = evaluate(path, tick.t_s);
    run.t_s.push_back(tick.t_s);
    for (std::size_t i = 0; i < axes; ++i) {
      const double err = want[i] - tick.y_true_m[i];
      const double meas = want[i] - tick.y_m[i];
      run.error_m[i].push_back(err);
      sum_sq[i] += err * err;
      sum_sq_meas[i] += meas * meas;
      run.stats[i].max_abs_true_m = std::max(run.stats[i].max_abs_true_m, std::abs(err));
    }
  });
  for (std::size_t i = 0; i < axes; ++i) {
    TrackingStats& s = run.stats[i];
    s.n = run.t_s.size();
    if (s.n == 0) continue;
    s.rms_true_m = std::sqrt(sum_sq[i] / static_cast<double>(s.n));
    s.rms_measured_m = std::sqrt(sum_sq_meas[i] / static_cast<double>(s.n));
  }
  run.stage_trips = sim.bridge().stage_trips();
}

// The decoupling a run uses: none, the stage's own coupling, or the one identified on it (refused:
// nullopt, the reason in run.reason).
std::optional<AxisCoupling> decoupling_of(const TrackingExperiment& e, const IdentifiedModels& models,
                                          const MultiAxisLoopConfig& c, const PathLoopOptions& o, PathRun& run) {
  if (!o.decouple) return AxisCoupling::identity(o.axes);
  if (!o.identified_decoupling) return c.stage.coupling;
  run.coupling_fit = identify_coupling(e, models, o);
  if (run.coupling_fit->ok()) return run.coupling_fit->coupling;
  run.refused = true;
  run.reason = "coupling identification: " + run.coupling_fit->reason;
  return std::nullopt;
}

}  // namespace

CouplingFitResult identify_coupling(const TrackingExperiment& e, const IdentifiedModels& models,
                                    const PathLoopOptions& o, double amplitude_V) {
  PathLoopOptions open_loop = o;
  open_loop.loop.servo = false;
  const MultiAxisLoopConfig c = path_loop_config(e, models, open_loop);
  MultiAxisLoopSimulation sim(c);
  const auto axes = static_cast<std::size_t>(sim.axes());
  ExperimentSpec spec;
  spec.amplitude_V = amplitude_V;
  spec.frequency_hz = 5.0;
  spec.duration_s = 0.8;
  std::array<std::array<std::vector<double>, kScanAxes>, kScanAxes> records;
  std::vector<AxisExcitation> experiments;
  sim.run(0.05);  // the first samples: each plan knows where its axis is
  for (std::size_t moved = 0; moved < axes; ++moved) {
    sim.compensator(static_cast<int>(moved)).start_experiment(spec);
    // The experiment starts at the next tick not yet planned (the horizon ahead) and lasts its
    // periods; the samples of its ticks (mode experiment on the moved axis) are what is fitted.
    sim.run(spec.duration_s + 0.2, [&](const MultiAxisTick& tick) {
      if (std::isnan(tick.y_ref_m[moved]) && tick.u_V[moved] != 0.0) {
        for (std::size_t j = 0; j < axes; ++j) records[moved][j].push_back(tick.y_m[j]);
      }
    });
    // After its experiment an axis approaches its reference again (over 0.5 s): the next axis's
    // experiment waits for it, or that motion would read as coupling.
    sim.run(1.0);
    AxisExcitation x;
    x.axis = static_cast<int>(moved);
    for (std::size_t j = 0; j < axes; ++j) x.y_m[j] = records[moved][j];
    experiments.push_back(x);
  }
  CouplingFitOptions fit;
  fit.axes = static_cast<int>(axes);
  return fit_coupling(experiments, fit);
}

RasterRun run_raster(const TrackingExperiment& e, const IdentifiedModels& models, const RasterOptions& o) {
  const MultiAxisLoopConfig c = path_loop_config(e, models, o);
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
  // The corners the compensator chooses for a line (1 ms without a stage model).
  const double corner_s = resonance_corner_s(c.compensator[0].stage);
  r.corner_s = corner_s > 0.0 ? corner_s : 1e-3;
  // r.centre_m stays 0 m: the middle of the voltage range, as the one-axis scans.
  r.start_s = kStartS;
  r.settle_s = 0.05;
  const double lines_end_s = r.start_s + r.lines / r.line_rate_hz;
  const std::optional<AxisCoupling> decoupling = decoupling_of(e, models, c, o, run);
  if (!decoupling) return run;
  run_path(sim, r, *decoupling, r.start_s, lines_end_s, r.start_s + raster_duration_s(r), run);
  return run;
}

LissajousRun run_lissajous(const TrackingExperiment& e, const IdentifiedModels& models, const LissajousOptions& o) {
  const MultiAxisLoopConfig c = path_loop_config(e, models, o);
  MultiAxisLoopSimulation sim(c);
  LissajousRun run;
  LissajousSpec& l = run.figure;
  l.amplitude_m = o.amplitude_m;
  l.frequency_hz = o.frequency_hz;
  l.phase_rad.fill(-0.5 * std::numbers::pi);  // each axis at its trough at the start: at rest
  l.duration_s = o.duration_s;
  l.start_s = kStartS;
  const double end_s = l.start_s + l.duration_s;
  const std::optional<AxisCoupling> decoupling = decoupling_of(e, models, c, o, run);
  if (!decoupling) return run;
  run_path(sim, l, *decoupling, l.start_s, end_s, end_s + 0.05, run);
  return run;
}

}  // namespace hystloop
