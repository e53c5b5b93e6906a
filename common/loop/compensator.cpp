#include "loop/compensator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

FeedforwardMode mode_of(ModelKind kind) noexcept {
  switch (kind) {
    case ModelKind::mem: return FeedforwardMode::kMem;
    case ModelKind::pi: return FeedforwardMode::kPi;
    case ModelKind::katalenic: return FeedforwardMode::kKatalenic;
    case ModelKind::linear: return FeedforwardMode::kLinear;
  }
  return FeedforwardMode::kOff;
}

std::optional<ModelKind> model_kind_of(FeedforwardMode mode) noexcept {
  switch (mode) {
    case FeedforwardMode::kMem: return ModelKind::mem;
    case FeedforwardMode::kPi: return ModelKind::pi;
    case FeedforwardMode::kKatalenic: return ModelKind::katalenic;
    case FeedforwardMode::kLinear: return ModelKind::linear;
    case FeedforwardMode::kOff:
    case FeedforwardMode::kExperiment: return std::nullopt;
  }
  return std::nullopt;
}

// The models' names are ModelKind's (models/model_set.cpp): one table for the compensator's
// config, HX_CONTROL's SET_MODE (hystloop-ctl mode) and the re-identifier's model choice.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field) {
  if (name == "off") return FeedforwardMode::kOff;
  if (const auto kind = parse_model_kind(name)) return mode_of(*kind);
  throw ParameterError(field, "unknown mode '" + name + "' (expected off, linear, mem, pi or katalenic)");
}

const char* to_string(FeedforwardMode mode) noexcept {
  if (mode == FeedforwardMode::kOff) return "off";
  if (mode == FeedforwardMode::kExperiment) return "experiment";
  if (const auto kind = model_kind_of(mode)) return to_string(*kind).data();  // a literal: NUL-terminated
  return "unknown";
}

void CompensatorConfig::validate() const {
  if (mode == FeedforwardMode::kExperiment) {
    throw ParameterError("compensator.mode", "'experiment' is started through HX_CONTROL, not selected as a mode");
  }
  mem.validate();
  pi.validate();
  katalenic.validate();
  linear.validate();
  require_in_range("compensator.dt_s", dt_s, 1e-6, 1.0);
  require_finite("compensator.u_min_V", u_min_V);
  require_finite("compensator.u_max_V", u_max_V);
  if (!(u_min_V < u_max_V)) throw ParameterError("compensator.u_max_V", "must exceed u_min_V");
  require_positive("compensator.slew_V_per_s", slew_V_per_s);
  require_in_range("compensator.reanchor_ticks", static_cast<double>(reanchor_ticks), 1.0, 1000.0);
  require_in_range("compensator.reanchor_ramp_ticks", static_cast<double>(reanchor_ramp_ticks), 1.0, 100000.0);
  require_in_range("compensator.slew_fraction", slew_fraction, 1e-3, 1.0);
  require_positive("compensator.reanchor_u_rate_V_per_s", reanchor_u_rate_V_per_s);
  if (horizon_ticks < 1 || horizon_ticks > kMaxHorizonTicks) {
    throw ParameterError("compensator.horizon_s", "must be 1 to " + std::to_string(kMaxHorizonTicks) + " ticks (got " +
                                                      std::to_string(horizon_ticks) + ")");
  }
}

Compensator::Compensator(const CompensatorConfig& config)
    : config_((config.validate(), config)),
      mode_(config.mode),
      mem_(config.mem),
      pi_(config.pi),
      katalenic_(config.katalenic),
      linear_(config.linear),
      pi_model_(config.pi),
      katalenic_model_(config.katalenic),
      anchor_offset_(config.reanchor_ticks, config.reanchor_ramp_ticks,
                     config.slew_fraction * config.slew_V_per_s * config.dt_s,
                     config.reanchor_u_rate_V_per_s * config.dt_s) {
  reversals_.reset(0.0);
}

bool Compensator::set_trajectory(TrajectorySpec spec, double start_s) {
  spec.validate();
  const bool given = !std::isnan(start_s);
  if (given && next_tick_ >= 0 && start_s - spec.blend_s < loop_time(next_tick_)) {
    trajectory_ = spec;
    trajectory_starts_now_ = true;
    trajectory_timed_ = false;
    return false;
  }
  if (given) {
    require_finite("trajectory.start_s", start_s);
    spec.start_s = start_s;
    spec.hold_m = last_ref_;
  }
  trajectory_ = spec;
  trajectory_starts_now_ = !given;
  trajectory_timed_ = given;
  return true;
}

void Compensator::offer_mem_params(const MemParams& params, std::int32_t version) {
  try {
    params.validate();
  } catch (const ParameterError&) {
    ++counters_.params_rejected;
    throw;
  }
  ModelParamSet set;
  set.mem = params;
  pending_ = Pending{set, false};
  pending_version_ = version;
  ++counters_.params_accepted;
}

void Compensator::offer_model(const ModelParamSet& params, std::int32_t version) {
  try {
    params.validate();
  } catch (const ParameterError&) {
    ++counters_.params_rejected;
    throw;
  }
  pending_ = Pending{params, true};
  pending_version_ = version;
  ++counters_.params_accepted;
}

ModelParamSet Compensator::model_params() const noexcept {
  ModelParamSet set;
  set.mem = mem_.params();
  set.pi = pi_.params();
  set.katalenic = katalenic_.params();
  set.linear = linear_.params();
  set.kind = model_kind_of(mode_).value_or(ModelKind::mem);
  return set;
}

double Compensator::nominal_slope() const noexcept {
  switch (mode_) {
    case FeedforwardMode::kMem: return mem_.params().c1;
    case FeedforwardMode::kPi: return pi_.params().weights[0];
    default: return linear_.params().gain;
  }
}

namespace {
// Model and inverse at the end of the monotone branch u_from -> u_to (from a virgin start at
// u_from); returns the output there.
template <class Model, class Inverse>
double replay_branch(Model& model, Inverse& inverse, double u_from, double u_to) noexcept {
  model.reset(u_from);
  const double y_from = model.output();
  const double y_to = model.forward(u_to);
  inverse.reset(y_from);
  inverse.inverse(y_to);
  return y_to;
}
}  // namespace

double Compensator::restart_at_reversal(FeedforwardMode mode, double u_rev) noexcept {
  // The state a periodic input leaves at a reversal: the branch from the previous reversal to
  // this one, replayed through the forward model (it sets every play / the operator that the
  // branch swept) and then through the inverse, which ends at u_rev.
  switch (mode) {
    case FeedforwardMode::kMem: mem_.reset_to_branch(last_ref_ - shift_m_, u_rev); return last_ref_ - shift_m_;
    case FeedforwardMode::kPi: return replay_branch(pi_model_, pi_, u_prev_rev_, u_rev);
    case FeedforwardMode::kKatalenic: return replay_branch(katalenic_model_, katalenic_, u_prev_rev_, u_rev);
    case FeedforwardMode::kLinear: {
      const double y0 = linear_.params().gain * u_rev + linear_.params().offset;
      linear_.reset(y0);
      return y0;
    }
    case FeedforwardMode::kOff:
    case FeedforwardMode::kExperiment: break;
  }
  return last_ref_ - shift_m_;
}

void Compensator::swap_params(std::int64_t k) noexcept {
  const ModelParamSet& p = pending_->params;
  const FeedforwardMode to = mode_of(p.kind);
  const bool switching = pending_->switch_model && mode_ != FeedforwardMode::kOff && to != mode_;
  const bool in_use = switching || to == mode_;
  const double u_shift = anchor_offset_.u_offset(k);
  const double u_rev = last_u_ - u_shift;  // this reversal, in the model's coordinates
  switch (p.kind) {
    case ModelKind::mem: mem_.set_params(p.mem); break;
    case ModelKind::pi: pi_.set_params(p.pi), pi_model_.set_params(p.pi); break;
    case ModelKind::katalenic: katalenic_.set_params(p.katalenic), katalenic_model_.set_params(p.katalenic); break;
    case ModelKind::linear: linear_.set_params(p.linear); break;
  }
  params_version_ = pending_version_;
  pending_.reset();
  ++counters_.params_swapped;
  if (!in_use) return;
  if (switching) {
    mode_ = to;
    ++counters_.model_switches;
  }
  // At a reversal the inverse starts a new branch from its last point: new parameters change
  // the slope of what follows, never the voltage already reached. MEM remembers nothing else;
  // the others restart at this reversal, and the offset takes up where their output is there.
  if (switching || mode_ != FeedforwardMode::kMem) {
    anchor_offset_.reset(last_ref_ - restart_at_reversal(mode_, u_rev), u_shift);
  }
  if (mode_ == FeedforwardMode::kLinear) {
    // A line has no branch to anchor: its fitted offset puts it through the middle of the loop,
    // where anchoring it at a reversal would put it at the loop's edge. Ramp back to that.
    anchor_offset_.ramp_to(0.0, u_shift, k, linear_.params().gain);
  } else {
    anchor_offset_.start_measuring(k);
  }
}

void Compensator::set_mode(FeedforwardMode mode) {
  if (mode == FeedforwardMode::kExperiment) {
    throw ParameterError("mode", "'experiment' is started with start_experiment()");
  }
  if (mode != mode_) {
    mode_ = mode;
    inverse_fresh_ = true;
    if (counters_.planned > 0) anchor_ = Anchor{last_u_, last_ref_, kNaN};
  }
}

void Compensator::start_experiment(const ExperimentSpec& spec) { experiments_.add(spec); }

void Compensator::stop_experiment() noexcept { experiments_.stop(loop_time(std::max<std::int64_t>(next_tick_, 0))); }

void Compensator::reset_inverse(double y0) noexcept {
  switch (mode_) {
    case FeedforwardMode::kMem:
      // A virgin stage starts on the skeleton; one that has moved (after an experiment or a
      // mode switch) is on a branch through where it is now, and the voltage must not jump.
      if (anchor_ && std::isfinite(anchor_->branch_u_V)) {
        // The stage is on the branch that began at branch_u_V (the experiment's last reversal)
        // and passes through the measured (u, y): continue it there, direction and all.
        mem_.continue_branch(anchor_->branch_u_V, anchor_->u_V, anchor_->y_m);
      } else if (anchor_) {
        mem_.reset_to_branch(anchor_->y_m, anchor_->u_V);
      } else {
        mem_.reset(y0);
      }
      break;
    case FeedforwardMode::kPi: pi_.reset(y0); break;
    case FeedforwardMode::kKatalenic: katalenic_.reset(y0); break;
    case FeedforwardMode::kLinear: linear_.reset(y0); break;
    case FeedforwardMode::kOff:
    case FeedforwardMode::kExperiment: break;
  }
}

double Compensator::feedforward(double y_ref) noexcept {
  switch (mode_) {
    case FeedforwardMode::kMem: return mem_.inverse(y_ref);
    case FeedforwardMode::kPi: return pi_.inverse(y_ref);
    case FeedforwardMode::kKatalenic: return katalenic_.inverse(y_ref);
    case FeedforwardMode::kLinear: return linear_.inverse(y_ref);
    case FeedforwardMode::kOff:
    case FeedforwardMode::kExperiment: return 0.0;
  }
  return 0.0;
}

void Compensator::observe(const CompensatorInput& sample) noexcept {
  if (sample.seq <= last_seq_) {
    ++counters_.out_of_order;
    return;
  }
  ++counters_.samples;
  if (last_seq_ >= 0) counters_.gaps += static_cast<std::uint64_t>(sample.seq - last_seq_ - 1);
  last_seq_ = sample.seq;
  if (next_tick_ < 0 || counters_.planned == 0) {  // nothing was due before the first plan
    next_tick_ = sample.seq + 1;
  } else if (next_tick_ <= sample.seq) {
    // The bridge is past what was planned (a stall longer than the horizon): plan from here on.
    counters_.ticks_behind += static_cast<std::uint64_t>(sample.seq + 1 - next_tick_);
    next_tick_ = sample.seq + 1;
  }
  plan_end_ = sample.seq + config_.horizon_ticks;
  if (awaiting_anchor_ && sample.seq >= anchor_tick_) {
    // The experiment's end has been measured: track again from where the stage is.
    awaiting_anchor_ = false;
    anchor_ = Anchor{sample.u_V, sample.y_m, experiment_branch_u_};
    restart_reference(loop_time(next_tick_), sample.y_m);
  }
  if (anchor_offset_.observe(sample.seq, sample.y_m, sample.u_V, next_tick_, nominal_slope())) ++counters_.reanchors;
}

void Compensator::take_params_from(const Compensator& old) noexcept {
  mem_.set_params(old.mem_params());
  pi_.set_params(old.pi_.params());
  pi_model_.set_params(old.pi_.params());
  katalenic_.set_params(old.katalenic_.params());
  katalenic_model_.set_params(old.katalenic_.params());
  linear_.set_params(old.linear_.params());
  params_version_ = old.params_version_;
  pending_ = old.pending_;
  pending_version_ = old.pending_version_;
}

void Compensator::restart_reference(double t_s, double from_m) noexcept {
  trajectory_.blend_s = std::max(trajectory_.blend_s, 0.5);
  const double earliest = t_s + trajectory_.blend_s;
  // A trajectory given a start time keeps it when it is still ahead; otherwise as soon as possible.
  trajectory_.start_s = trajectory_timed_ ? std::max(trajectory_.start_s, earliest) : earliest;
  trajectory_.hold_m = from_m;
  trajectory_starts_now_ = false;
  last_ref_ = from_m;
  reversals_.reset(from_m);
  inverse_fresh_ = true;
}

std::size_t Compensator::plan(std::span<CommandTick> out) noexcept {
  std::size_t n = 0;
  while (n < out.size() && next_tick_ >= 0 && next_tick_ <= plan_end_) {
    out[n++] = plan_tick(next_tick_++);
    ++counters_.planned;
  }
  return n;
}

CommandTick Compensator::plan_tick(std::int64_t k) noexcept {
  constexpr auto kExperimentMode = static_cast<std::int8_t>(FeedforwardMode::kExperiment);
  const ExperimentQueue::Step e = experiments_.step(loop_time(k));
  if (e.active) {
    if (!in_experiment_) {
      experiment_u_.reset(e.voltage_V);
      in_experiment_ = true;
    } else {
      experiment_u_.update(e.voltage_V);
    }
    last_u_ = e.voltage_V;
    return {k, e.voltage_V, kNaN, params_version_, kExperimentMode};
  }
  if (e.ended) {
    awaiting_anchor_ = true;
    anchor_tick_ = k;
    in_experiment_ = false;
    experiment_branch_u_ = experiment_u_.turning_point();
  }
  if (awaiting_anchor_) return {k, last_u_, kNaN, params_version_, static_cast<std::int8_t>(mode_)};
  return tracking_tick(k);
}

CommandTick Compensator::tracking_tick(std::int64_t k) noexcept {
  const double t = loop_time(k);
  if (trajectory_starts_now_) {
    trajectory_.start_s = t + trajectory_.blend_s;
    trajectory_.hold_m = last_ref_;
    trajectory_starts_now_ = false;
  }
  const double y_ref = evaluate(trajectory_, t);
  if (reversals_.update(y_ref) == ReversalDetector::Event::kReversal) {
    ++counters_.reversals;
    if (pending_) swap_params(k);
    u_prev_rev_ = last_u_ - anchor_offset_.u_offset(k);
  }
  if (inverse_fresh_) {
    reset_inverse(y_ref);
    inverse_fresh_ = false;
    anchor_.reset();
    if (anchor_offset_.measuring()) ++counters_.reanchors_skipped;
    anchor_offset_.reset(0.0);
    u_prev_rev_ = last_u_;
  }
  shift_m_ = anchor_offset_.y_offset(k);
  const double shift_V = anchor_offset_.u_offset(k);
  const double y_model = y_ref - shift_m_;
  const double u_model = feedforward(y_model);
  double u = u_model + shift_V;
  if (!std::isfinite(u)) {  // never hand a non-finite voltage on
    ++counters_.nonfinite_outputs;
    u = last_u_;
  }
  if (u < config_.u_min_V || u > config_.u_max_V) {
    ++counters_.u_clamped;
    u = std::clamp(u, config_.u_min_V, config_.u_max_V);
  }
  anchor_offset_.planned(k, y_model, u - shift_V);
  last_ref_ = y_ref;
  last_u_ = u;
  return {k, u, y_ref, params_version_, static_cast<std::int8_t>(mode_)};
}

}  // namespace hystloop
