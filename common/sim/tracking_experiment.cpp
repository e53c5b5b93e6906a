#include "sim/tracking_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/errors.hpp"

#include "ident/katalenic_fit.hpp"
#include "ident/linear_fit.hpp"
#include "ident/model_selection.hpp"
#include "ident/online_mem_estimator.hpp"
#include "ident/pi_fit.hpp"
#include "ident/stage_removal.hpp"

namespace hystloop {

LoopSimulationConfig tracking_loop_config(const TrackingExperiment& e) {
  LoopSimulationConfig c;
  c.stage.noise_rms_m = e.noise_rms_m;
  c.stage.seed = e.seed;
  c.stage.plant = e.plant;
  c.stage.ramberg_osgood = e.ramberg_osgood;
  c.stage.hysteresis = e.series_hysteresis;
  c.stage.linear = e.series_stage;
  c.compensator.mode = FeedforwardMode::kOff;
  return c;
}

TrackingExperiment two_mode_experiment() {
  TrackingExperiment e;
  e.plant = PlantKind::kSeries;
  e.series_stage = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5e-4);
  return e;
}

void use_models(LoopSimulationConfig& c, const IdentifiedModels& models, const MemParams& mem) {
  c.compensator.models.mem = mem;
  c.compensator.models.pi = models.pi;
  c.compensator.models.katalenic = models.katalenic;
  c.compensator.models.linear = models.linear;
  c.compensator.u_min_V = c.limits.u_min_V;
  c.compensator.u_max_V = c.limits.u_max_V;
  c.compensator.slew_V_per_s = c.limits.slew_V_per_s;
}

IdentifiedModels identify_models_through_loop(const TrackingExperiment& e) {
  ExperimentSpec input;  // 250 V, 10 Hz: the MEM paper's identification input
  input.duration_s = e.identify_s;
  return identify_models_through_loop(e, input);
}

IdentifiedModels identify_models_through_loop(const TrackingExperiment& e, const ExperimentSpec& input,
                                              const StageModel& removed) {
  constexpr double kLeadIn = 0.01;  // the first ticks hold 0 V while the compensator starts
  const LoopSimulationConfig config = tracking_loop_config(e);
  LoopSimulation sim(config);
  sim.compensator().start_experiment(input);
  sim.run(input.duration_s + kLeadIn);
  std::vector<double> u, y;
  StageRemoval removal(removed, config.compensator.dt_s);
  HysteresisSample ready[2];
  auto keep = [&](const HysteresisSample& s) {
    u.push_back(s.u);
    y.push_back(s.y);
  };
  for (const LoopTick& t : sim.history()) {
    if (t.t_s < kLeadIn || t.t_s > input.duration_s) continue;
    const std::size_t n = removal.feed(t.u_V, t.y_m, ready);
    for (std::size_t i = 0; i < n; ++i) keep(ready[i]);
  }
  if (const auto held = removal.reset()) keep(*held);
  IdentifiedModels m;
  m.mem_fit = fit_mem(u, y);
  m.mem = m.mem_fit.params;
  const PiFitResult pi = fit_pi(u, y);
  const KatalenicFitResult kat = fit_katalenic(u, y);
  const LinearFitResult lin = fit_linear(u, y);
  m.ok = m.mem_fit.ok() && pi.ok() && kat.ok() && lin.ok();
  if (pi.ok()) m.pi = to_pi_params(pi);
  m.katalenic = kat.params;
  if (lin.ok()) m.linear = to_linear_params(lin);
  const ModelSelection selection = select_model(u, y);
  for (const ModelScore& score : selection.ranking) {
    if (score.status == FitStatus::ok) m.ranking.push_back(score.kind);
  }
  return m;
}

namespace {

double rms_true(const std::vector<LoopTick>& h, double from_s, double to_s) {
  double ss = 0.0;
  std::size_t n = 0;
  for (const LoopTick& t : h) {
    if (t.t_s < from_s || t.t_s >= to_s || !std::isfinite(t.y_ref_m)) continue;
    ss += (t.y_ref_m - t.y_true_m) * (t.y_ref_m - t.y_true_m);
    ++n;
  }
  return n > 0 ? std::sqrt(ss / static_cast<double>(n)) : 0.0;
}

// Swaps as the bridge applied them, each judged on the 5 s before and after it.
void judge_swaps(const std::vector<LoopTick>& h, double margin, TrackingRun& run) {
  constexpr double kWindow = 5.0;
  std::int32_t version = h.empty() ? 0 : h.front().params_version;
  const double end = h.empty() ? 0.0 : h.back().t_s;
  for (const LoopTick& t : h) {
    if (t.params_version == version) continue;
    version = t.params_version;
    SwapRecord s{t.t_s, version, rms_true(h, t.t_s - kWindow, t.t_s), rms_true(h, t.t_s, t.t_s + kWindow), false};
    // Judged only with at least a second of reference on both sides.
    s.worse = t.t_s + 1.0 <= end && s.rms_before_m > 0.0 && s.rms_after_m > (1.0 + margin) * s.rms_before_m;
    run.worse_swaps += s.worse ? 1 : 0;
    run.swaps.push_back(s);
  }
}

}  // namespace

TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, const TrackingOptions& o) {
  LoopSimulationConfig c = tracking_loop_config(e);
  c.stage.drift_fraction = e.drift_fraction;
  c.stage.drift_duration_s = e.drift_duration_s;
  c.compensator.mode = o.mode;
  use_models(c, models, o.start_mem);
  if (o.feedback) {
    c.servo.kp = e.kp;
    c.servo.ki = e.ki;
    c.servo.nominal_gain_m_per_V = models.linear.gain;
  }
  LoopSimulation sim(c);
  const TrajectorySpec reference = mem_paper_reference(0.5, 0.5, 0.0);  // approach over 0.5 s
  sim.compensator().set_trajectory(reference, reference.start_s);

  OnlineMemOptions opt;
  opt.window_samples = static_cast<std::size_t>(std::llround(o.window_s / c.compensator.dt_s));
  opt.fit.reversal_dead_band_V = 1.0;  // feedback jitter on u is not a branch
  OnlineMemEstimator estimator(opt, c.compensator.models.mem);
  MemWindow window = estimator.make_window();
  OnlineSelectorOptions selector = o.selector;
  selector.selection.mem.reversal_dead_band_V = opt.fit.reversal_dead_band_V;
  TrackingRun run;
  std::int32_t version = 1;
  const auto refit_every = std::max<std::int64_t>(1, std::llround(o.refit_every_s / c.compensator.dt_s));
  auto offer = [&](const ModelParamSet& set) {
    try {
      if (o.reidentify == Reidentify::mem) {
        sim.compensator().offer_mem_params(set.mem, ++version);
      } else {
        sim.compensator().offer_model(set, ++version);
      }
    } catch (const ParameterError&) {
      ++run.offers_refused;
    }
  };
  FeedforwardMode mode = o.mode;
  sim.run(e.track_s, [&](const LoopTick& t) {
    if (sim.compensator().mode() != mode) {  // planned up to a horizon ahead of t
      mode = sim.compensator().mode();
      run.first_kind_time_s = t.t_s;
    }
    if (o.reidentify == Reidentify::off) return;
    estimator.feed(t.u_V, t.y_m);
    if (t.k == 0 || t.k % refit_every != 0) return;
    if (o.reidentify == Reidentify::mem) {
      if (estimator.refit().accepted) {
        ModelParamSet set;
        set.mem = estimator.params();
        offer(set);
      }
      return;
    }
    estimator.snapshot(window);
    if (window.poison != PoisonKind::none) return;
    const ModelProposal p = propose_model(window.u, window.y, sim.compensator().model_params(), selector);
    if (p.proposes()) offer(p.params);
  });
  run.stats = sim.tracking(e.settle_s, e.track_s);
  run.params_version = sim.compensator().params_version();
  run.final_mem = sim.compensator().mem_params();
  run.final_mode = sim.compensator().mode();
  run.final_kind = sim.compensator().model_params().kind;
  run.counters = sim.compensator().counters();
  for (double t = 0.0; t + 0.5 < e.track_s; t += 1.0)
    run.rms_per_second_m.push_back(rms_true(sim.history(), t, t + 1.0));
  judge_swaps(sim.history(), selector.margin, run);
  return run;
}

TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, FeedforwardMode mode,
                         bool feedback, bool reidentify, const MemParams& start_mem) {
  TrackingOptions o;
  o.mode = mode;
  o.feedback = feedback;
  o.reidentify = reidentify ? Reidentify::mem : Reidentify::off;
  o.start_mem = start_mem;
  return run_tracking(e, models, o);
}

}  // namespace hystloop
