#include "sim/scan_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"

namespace hystloop {

std::vector<ScanReference> scan_references() {
  return {{"triangle 10 Hz 1 um", TrajectoryShape::kTriangle, 1e-6, 10.0},
          {"triangle 50 Hz 1 um", TrajectoryShape::kTriangle, 1e-6, 50.0},
          {"sine 10 Hz 1 um", TrajectoryShape::kSine, 1e-6, 10.0},
          {"sine 50 Hz 1 um", TrajectoryShape::kSine, 1e-6, 50.0},
          {"sine 100 Hz 0.5 um", TrajectoryShape::kSine, 0.5e-6, 100.0},
          {"sine 200 Hz 0.25 um", TrajectoryShape::kSine, 0.25e-6, 200.0}};
}

IdentifiedModels identify_for_scan(const TrackingExperiment& e, double amplitude_m, const StageModel& removed) {
  ExperimentSpec input;
  input.amplitude_V = 160.0 * std::abs(amplitude_m) / 1e-6;
  input.frequency_hz = 10.0;
  input.duration_s = 2.0;
  return identify_models_through_loop(e, input, removed);
}

StageModel scan_stage(const TrackingExperiment& e, const ScanOptions& o) {
  StageModel stage;
  if (o.stage_inverse && e.plant == PlantKind::kBanning) {
    const SimulatedStageConfig plant = tracking_loop_config(e).stage;
    stage.kind = StageModel::Kind::kSecondOrder;
    stage.second_order = plant.banning.stage;
    stage.order = plant.banning.order;
  } else if (o.stage_inverse && e.plant == PlantKind::kSeries) {
    stage.kind = StageModel::Kind::kLinear;  // the plant's own stage, delay included
    stage.linear = o.stage_model ? *o.stage_model : e.series_stage;
    stage.known_to_hz = o.stage_known_to_hz;
  }
  return stage;
}

LoopSimulationConfig scan_loop_config(const TrackingExperiment& e, const IdentifiedModels& models,
                                      const ScanOptions& o) {
  LoopSimulationConfig c = tracking_loop_config(e);
  c.compensator.mode = o.mode.value_or(models.ranking.empty() ? FeedforwardMode::kPi : mode_of(models.ranking.front()));
  use_models(c, models, models.mem);
  if (o.stage_inverse) {
    // Only the stage's own fields: preview and reference bandwidth stay as the config sets them.
    const StageModel stage = scan_stage(e, o);
    c.compensator.stage.kind = stage.kind;
    c.compensator.stage.second_order = stage.second_order;
    c.compensator.stage.order = stage.order;
    c.compensator.stage.linear = stage.linear;
    c.compensator.stage.known_to_hz = stage.known_to_hz;
  }
  c.compensator.learning.enabled = o.learning;
  c.compensator.servo_slew_reserve = o.servo_slew_reserve;
  c.block_ticks = o.block_ticks;
  if (o.servo) {
    c.servo.kp = o.kp;
    c.servo.ki = o.ki;
    c.servo.notch_hz = o.notch_hz;
    c.servo.notch_q = o.notch_q;
    c.servo.notch2_hz = o.notch2_hz;
    c.servo.notch2_q = o.notch2_q;
    c.servo.nominal_gain_m_per_V = models.linear.gain;
  }
  return c;
}

ScanRun run_scan(const TrackingExperiment& e, const IdentifiedModels& models, const ScanReference& r,
                 const ScanOptions& o) {
  const LoopSimulationConfig c = scan_loop_config(e, models, o);
  LoopSimulation sim(c);
  TrajectorySpec spec;
  spec.shape = r.shape;
  spec.amplitude_m = r.amplitude_m;
  spec.frequency_hz = r.frequency_hz;
  spec.blend_s = 0.2;
  spec.shape_if_infeasible = o.shape_if_infeasible;
  const double start_s = 0.3;
  ScanRun run;
  run.mode = c.compensator.mode;
  sim.run(0.05);  // the first samples: the plan knows where the loop is
  try {
    const TrajectoryVerdict v = sim.compensator().take_trajectory(spec, start_s);
    run.reason = v.note;
    run.shaped = v.shaped;
    run.amplitude_m = v.spec.amplitude_m;
    run.corner_s = v.spec.corner_s;
  } catch (const ParameterError& err) {
    run.refused = true;
    run.reason = err.what();
    return run;
  }
  const double period = 1.0 / r.frequency_hz;
  const int measure = std::max(o.measure_periods, static_cast<int>(std::ceil(o.min_measure_s / period)));
  const double from = start_s + o.settle_periods * period;
  const double to = from + measure * period;
  sim.run(to + 1e-9 - sim.now_s());
  run.stats = sim.tracking(from, to);
  run.counters = sim.compensator().counters();
  const std::vector<LoopTick>& h = sim.history();
  for (const LoopTick& t : h) {
    if (t.t_s >= start_s - spec.blend_s && (t.flags & (sample_flags::kSaturated | sample_flags::kSlewLimited)))
      ++run.clamped_ticks;
  }
  const int periods = static_cast<int>(std::floor((to - start_s) / period + 1e-9));
  for (int p = 0; p < periods; ++p)
    run.rms_per_period_m.push_back(sim.tracking(start_s + p * period, start_s + (p + 1) * period).rms_true_m);
  for (int p = periods - 1; p >= 0 && run.rms_per_period_m[static_cast<std::size_t>(p)] <= 1e-9; --p)
    run.periods_to_converge = p;
  return run;
}

}  // namespace hystloop
