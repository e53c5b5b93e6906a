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

FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field) {
  if (name == "off") return FeedforwardMode::kOff;
  if (name == "linear") return FeedforwardMode::kLinear;
  if (name == "mem") return FeedforwardMode::kMem;
  if (name == "pi") return FeedforwardMode::kPi;
  if (name == "katalenic") return FeedforwardMode::kKatalenic;
  throw ParameterError(field, "unknown mode '" + name + "' (expected off, linear, mem, pi or katalenic)");
}

const char* to_string(FeedforwardMode mode) noexcept {
  switch (mode) {
    case FeedforwardMode::kOff: return "off";
    case FeedforwardMode::kLinear: return "linear";
    case FeedforwardMode::kMem: return "mem";
    case FeedforwardMode::kPi: return "pi";
    case FeedforwardMode::kKatalenic: return "katalenic";
    case FeedforwardMode::kExperiment: return "experiment";
  }
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
  if (horizon_ticks < 1 || horizon_ticks > kMaxHorizonTicks) {
    throw ParameterError("compensator.horizon_s", "must be 1 to " + std::to_string(kMaxHorizonTicks) +
                                                      " ticks (got " + std::to_string(horizon_ticks) + ")");
  }
}

Compensator::Compensator(const CompensatorConfig& config)
    : config_((config.validate(), config)),
      mode_(config.mode),
      mem_(config.mem),
      pi_(config.pi),
      katalenic_(config.katalenic),
      linear_(config.linear) {
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
  pending_mem_ = params;
  pending_version_ = version;
  ++counters_.params_accepted;
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
}

void Compensator::take_params_from(const Compensator& old) noexcept {
  mem_.set_params(old.mem_params());
  params_version_ = old.params_version_;
  pending_mem_ = old.pending_mem_;
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
    if (pending_mem_) {
      // At a reversal the inverse starts a new branch from its last point: swapping here
      // changes the slope of what follows, never the voltage already reached.
      mem_.set_params(*pending_mem_);
      params_version_ = pending_version_;
      pending_mem_.reset();
      ++counters_.params_swapped;
    }
  }
  if (inverse_fresh_) {
    reset_inverse(y_ref);
    inverse_fresh_ = false;
    anchor_.reset();
  }
  double u = feedforward(y_ref);
  if (!std::isfinite(u)) {  // never hand a non-finite voltage on
    ++counters_.nonfinite_outputs;
    u = last_u_;
  }
  last_ref_ = y_ref;
  last_u_ = u;
  return {k, u, y_ref, params_version_, static_cast<std::int8_t>(mode_)};
}

}  // namespace hystloop
