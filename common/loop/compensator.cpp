#include "loop/compensator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "core/errors.hpp"
#include "loop/reference_admission.hpp"

namespace hystloop {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string si(double value, const char* unit) { return number_text(value, 3) + " " + unit; }
}  // namespace

Compensator::Compensator(const CompensatorConfig& config)
    : planner_((config.validate(), config)),
      // Samples arrive up to the horizon after their tick was planned, plus a block or two; a
      // stage inverted with preview asks the learning for its correction that much earlier.
      learner_(learning_for_stage(config.learning, config.stage, config.dt_s), config.dt_s,
               config.horizon_ticks + 2000 + (config.stage.is_linear() ? PreviewStageInverse::kMaxPreviewTicks : 0)) {}

void Compensator::observe(const CompensatorInput& sample) noexcept {
  if (const auto y = planner_.observe(sample)) learner_.observe(sample.seq, *y);
}

std::size_t Compensator::plan(std::span<CommandTick> out) noexcept { return planner_.plan(out, &learner_); }

void Compensator::set_learning(bool on) noexcept { learner_.set_enabled(on); }

void Compensator::reset_learning() noexcept { learner_.reset(); }

bool Compensator::set_trajectory(TrajectorySpec spec, double start_s) { return take_trajectory(spec, start_s).started; }

TrajectoryVerdict Compensator::take_trajectory(TrajectorySpec spec, double start_s) {
  TrajectoryVerdict v;
  try {
    v = check_trajectory(planner_, spec, start_s, learner_.enabled());
  } catch (const ParameterError&) {
    count_refused_trajectory();
    throw;
  }
  return commit_trajectory(std::move(v), start_s);
}

TrajectoryVerdict Compensator::check_trajectory(const FeedforwardPlanner& snapshot, TrajectorySpec spec, double start_s,
                                                bool learning_enabled) {
  spec.validate();
  if (!std::isnan(start_s)) require_finite("trajectory.start_s", start_s);
  return ReferenceAdmission(snapshot).admit_trajectory(spec, start_s, learning_enabled);
}

TrajectoryVerdict Compensator::commit_trajectory(TrajectoryVerdict checked, double start_s) {
  TrajectoryVerdict v = std::move(checked);
  if (v.shaped) ++planner_.counters().trajectories_shaped;
  const ReferenceAdmission admission(planner_);
  planner_.set_learning_room(admission.leaves_room_for_learning(v.extent));
  const std::int64_t next = planner_.next_tick();
  v.started = std::isnan(start_s) || next < 0 || start_s - v.spec.blend_s >= planner_.loop_time(next);
  planner_.apply_trajectory(v.spec, start_s);
  v.spec = planner_.trajectory();
  return v;
}

PlanExtent Compensator::dry_run(const TrajectorySpec& spec, double start_s) const {
  return ReferenceAdmission(planner_).dry_run(spec, start_s);
}

PlanExtent Compensator::dry_run_periodic(const TrajectorySpec& spec) const {
  return ReferenceAdmission(planner_).dry_run_periodic(spec);
}

TrajectoryVerdict Compensator::take_scan(const ScanShare& share, double blend_s) {
  const PlanExtent e = check_scan(share, blend_s);
  return apply_scan(share, blend_s, e);
}

PlanExtent Compensator::check_scan(const ScanShare& share, double blend_s) {
  require_in_range("scan.blend_s", blend_s, 0.0, 60.0);
  scan_hold(share, blend_s).validate();
  try {
    return ReferenceAdmission(planner_).admit_scan(share, blend_s);
  } catch (const ParameterError&) {
    ++planner_.counters().plan_refusals;
    throw;
  }
}

TrajectoryVerdict Compensator::apply_scan(const ScanShare& share, double blend_s, const PlanExtent& checked) {
  TrajectoryVerdict v;
  v.extent = checked;
  planner_.set_learning_room(ReferenceAdmission(planner_).leaves_room_for_learning(checked));
  planner_.apply_trajectory(scan_hold(share, blend_s), share.start_s(), &share);
  v.spec = planner_.trajectory();
  return v;
}

void take_scan_on_every_axis(std::span<Compensator* const> laws, std::span<const ScanShare> shares, double blend_s) {
  if (laws.size() != shares.size()) throw ParameterError("scan", "one share per axis");
  std::array<PlanExtent, kMaxAxes> checked{};
  if (laws.size() > checked.size()) throw ParameterError("scan", "at most " + std::to_string(kMaxAxes) + " axes");
  for (std::size_t i = 0; i < laws.size(); ++i) checked[i] = laws[i]->check_scan(shares[i], blend_s);
  for (std::size_t i = 0; i < laws.size(); ++i) laws[i]->apply_scan(shares[i], blend_s, checked[i]);
}

void Compensator::offer_mem_params(const MemParams& params, std::int32_t version) {
  ModelParamSet set;
  set.mem = params;
  offer(set, false, version);
}

void Compensator::offer_model(const ModelParamSet& params, std::int32_t version) { offer(params, true, version); }

void Compensator::offer(const ModelParamSet& set, bool switch_model, std::int32_t version) {
  try {
    if (switch_model) {
      set.validate(config().dt_s);
    } else {
      set.mem.validate();  // MEM's parameters only: the rest of the set is not offered
    }
    ReferenceAdmission(planner_).check_line_under(set, switch_model);
  } catch (const ParameterError&) {
    ++planner_.counters().params_rejected;
    throw;
  }
  planner_.exchange().offer(set, switch_model, version);
  ++planner_.counters().params_accepted;
}

ModelParamSet Compensator::model_params() const noexcept {
  ModelParamSet set;
  planner_.inverses().get_params(set);
  set.kind = model_kind_of(mode()).value_or(ModelKind::mem);
  return set;
}

bool Compensator::params_held_by_learning() const noexcept {
  return planner_.exchange().held_by_learning(mode(), learner_.figures(), config().learning);
}

void Compensator::set_mode(FeedforwardMode mode) {
  if (mode == FeedforwardMode::kExperiment) {
    throw ParameterError("mode", "'experiment' is started with start_experiment()");
  }
  planner_.set_mode(mode);
}

void Compensator::start_experiment(const ExperimentSpec& requested) {
  requested.validate();
  const CompensatorConfig& c = config();
  if (requested.multisine) {
    ExperimentSpec spec = requested;
    prepare_experiment(spec, c.dt_s);
    check_multisine(spec);
    planner_.start_experiment(spec);
    return;
  }
  const ExperimentSpec& spec = requested;
  // An excitation is a voltage: it must fit the actuator as it is, not be clamped by the bridge.
  if (spec.offset_V - spec.amplitude_V < c.u_min_V || spec.offset_V + spec.amplitude_V > c.u_max_V) {
    throw ParameterError("experiment", "offset " + si(spec.offset_V, "V") + " +- amplitude " +
                                           si(spec.amplitude_V, "V") + " leaves the actuator's range " +
                                           si(c.u_min_V, "V") + " to " + si(c.u_max_V, "V") +
                                           " (actuator.u_min_V/u_max_V)");
  }
  const double rate = 2.0 * std::numbers::pi * spec.frequency_hz * spec.amplitude_V;
  if (rate > c.plan_slew_fraction * c.slew_V_per_s) {
    throw ParameterError(
        "experiment",
        "a sine of " + si(spec.amplitude_V, "V") + " at " + si(spec.frequency_hz, "Hz") + " needs " + si(rate, "V/s") +
            ", above " + si(100.0 * c.plan_slew_fraction, "%") + " of the slew limit " + si(c.slew_V_per_s, "V/s") +
            " (actuator.slew_V_per_s): at most " +
            si(c.plan_slew_fraction * c.slew_V_per_s / (2.0 * std::numbers::pi * spec.amplitude_V), "Hz") +
            " at this amplitude");
  }
  planner_.start_experiment(spec);
}

void Compensator::check_multisine(const ExperimentSpec& spec) const {
  const CompensatorConfig& c = config();
  const std::vector<double>& u = spec.samples->u_V;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  if (*lo < c.u_min_V || *hi > c.u_max_V) {
    throw ParameterError("experiment", "the multisine spans " + si(*lo, "V") + " to " + si(*hi, "V") +
                                           ", outside the actuator's range " + si(c.u_min_V, "V") + " to " +
                                           si(c.u_max_V, "V") + " (actuator.u_min_V/u_max_V)");
  }
  double rate = 0.0;
  for (std::size_t k = 1; k < u.size(); ++k) rate = std::max(rate, std::abs(u[k] - u[k - 1]) / c.dt_s);
  if (rate > c.plan_slew_fraction * c.slew_V_per_s) {
    throw ParameterError("experiment", "the multisine needs " + si(rate, "V/s") + ", above " +
                                           si(100.0 * c.plan_slew_fraction, "%") + " of the slew limit " +
                                           si(c.slew_V_per_s, "V/s") +
                                           " (actuator.slew_V_per_s): a lower amplitude or f_max");
  }
}

void Compensator::stop_experiment() noexcept { planner_.stop_experiment(); }

Compensator Compensator::restarted(CompensatorConfig config, std::string& refusal) const {
  config.models.mem = mem_params();
  config.mode = mode();
  TrajectorySpec reference = trajectory();
  reference.hold_m = 0.0;
  Compensator next(config);
  // The parameter sets given here: the one in use with its version, and one waiting for a reversal.
  next.planner_.carry_params_over(planner_);
  next.learner_.set_enabled(learner_.enabled());
  refusal.clear();
  try {
    next.set_trajectory(reference, kNaN);
  } catch (const ParameterError& e) {
    // Taken before, infeasible now (the sets in use changed since): hold where the new law starts
    // rather than clamp; the operator sends it again, or a feasible one.
    next.set_trajectory(TrajectorySpec{}, kNaN);
    refusal = e.what();
  }
  return next;
}

}  // namespace hystloop
