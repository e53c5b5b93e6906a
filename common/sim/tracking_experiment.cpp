#include "loop/tracking_experiment.hpp"

#include <vector>

#include "ident/katalenic_fit.hpp"
#include "ident/linear_fit.hpp"
#include "ident/online_mem_estimator.hpp"
#include "ident/pi_fit.hpp"

namespace hystloop {

LoopSimulationConfig tracking_loop_config(const TrackingExperiment& e) {
  LoopSimulationConfig c;
  c.stage.noise_rms_m = e.noise_rms_m;
  c.stage.seed = e.seed;
  c.compensator.mode = FeedforwardMode::kOff;
  return c;
}

IdentifiedModels identify_models_through_loop(const TrackingExperiment& e) {
  constexpr double kLeadIn = 0.01;  // the first ticks hold 0 V while the compensator starts
  LoopSimulation sim(tracking_loop_config(e));
  ExperimentSpec input;  // 250 V, 10 Hz: the MEM paper's identification input
  input.duration_s = e.identify_s;
  sim.compensator().start_experiment(input);
  sim.run(e.identify_s + kLeadIn);
  std::vector<double> u, y;
  for (const LoopTick& t : sim.history()) {
    if (t.t_s < kLeadIn || t.t_s > e.identify_s) continue;
    u.push_back(t.u_V);
    y.push_back(t.y_m);
  }
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
  return m;
}

TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, FeedforwardMode mode,
                         bool feedback, bool reidentify, const MemParams& start_mem) {
  LoopSimulationConfig c = tracking_loop_config(e);
  c.compensator.mode = mode;
  c.compensator.mem = start_mem;
  c.compensator.pi = models.pi;
  c.compensator.katalenic = models.katalenic;
  c.compensator.linear = models.linear;
  if (feedback) {
    c.servo.kp = e.kp;
    c.servo.ki = e.ki;
    c.servo.nominal_gain_m_per_V = models.linear.gain;
  }
  LoopSimulation sim(c);
  const TrajectorySpec reference = mem_paper_reference(0.5, 0.5, 0.0);  // approach over 0.5 s
  sim.compensator().set_trajectory(reference, reference.start_s);

  OnlineMemOptions opt;
  opt.window_samples = 40000;          // 4 s: four branches of the 1 Hz reference
  opt.fit.reversal_dead_band_V = 1.0;  // feedback jitter on u is not a branch
  OnlineMemEstimator estimator(opt, c.compensator.mem);
  std::int32_t version = 1;
  const auto refit_every = static_cast<std::int64_t>(1.0 / c.compensator.dt_s);
  sim.run(e.track_s, [&](const LoopTick& t) {
    if (!reidentify) return;
    estimator.feed(t.u_V, t.y_m);
    if (t.k > 0 && t.k % refit_every == 0 && estimator.refit().accepted) {
      sim.compensator().offer_mem_params(estimator.params(), ++version);
    }
  });
  return {sim.tracking(e.settle_s, e.track_s), sim.compensator().params_version(), sim.compensator().mem_params()};
}

}  // namespace hystloop
