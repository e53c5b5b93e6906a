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
  feedback.validate();
  if (lead_ticks < 1 || lead_ticks > 32) {
    throw ParameterError("compensator.lead_ticks", "must be in [1, 32] (got " + std::to_string(lead_ticks) + ")");
  }
  require_in_range("compensator.dt_s", dt_s, 1e-6, 1.0);
}

void ExperimentSpec::validate() const {
  require_positive("experiment.amplitude_V", amplitude_V);
  require_finite("experiment.offset_V", offset_V);
  require_positive("experiment.frequency_hz", frequency_hz);
  require_positive("experiment.duration_s", duration_s);
}

ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s) {
  if (kind != "sine" && kind != "settle") {
    throw ParameterError("experiment", "'" + std::string(kind) + "' unknown (sine, or settle: a sine identification skips)");
  }
  const ExperimentSpec spec{amplitude_V, offset_V, frequency_hz, duration_s, kind == "settle"};
  spec.validate();
  return spec;
}

double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept {
  return spec.offset_V + spec.amplitude_V * std::sin(2.0 * std::numbers::pi * spec.frequency_hz * t_s);
}

double experiment_end_s(double start_s, const ExperimentSpec& spec) noexcept {
  const double periods = std::ceil(spec.duration_s * spec.frequency_hz - 1e-9);
  return start_s + periods / spec.frequency_hz;
}

std::int64_t first_tick_at_or_after(double t_s, double dt_s) noexcept {
  auto k = static_cast<std::int64_t>(std::ceil(t_s / dt_s));
  // The compensator compares static_cast<double>(k) * dt with t: settle the rounding the same way.
  while (k > 0 && static_cast<double>(k - 1) * dt_s >= t_s) --k;
  while (static_cast<double>(k) * dt_s < t_s) ++k;
  return k;
}

std::vector<ExperimentTicks> experiment_schedule(std::int64_t first_tick, std::span<const ExperimentSpec> specs,
                                                 double dt_s) {
  std::vector<ExperimentTicks> ticks;
  ticks.reserve(specs.size());
  double start_s = static_cast<double>(first_tick) * dt_s;  // Compensator::loop_time
  std::int64_t begin = first_tick;
  for (const ExperimentSpec& spec : specs) {
    const double end_s = experiment_end_s(start_s, spec);
    const std::int64_t end = std::max(begin, first_tick_at_or_after(end_s, dt_s));
    ticks.push_back({begin, end});
    begin = end;
    start_s = end_s;
  }
  return ticks;
}

Compensator::Compensator(const CompensatorConfig& config)
    : config_((config.validate(), config)),
      mode_(config.mode),
      mem_(config.mem),
      pi_(config.pi),
      katalenic_(config.katalenic),
      linear_(config.linear),
      feedback_(config.feedback) {
  ref_tick_.fill(-1);
}

void Compensator::set_trajectory(const TrajectorySpec& spec) {
  spec.validate();
  trajectory_ = spec;
}

void Compensator::start_trajectory_now(TrajectorySpec spec) {
  spec.start_s = loop_time(last_seq_ + config_.lead_ticks + 1) + spec.blend_s;
  spec.hold_m = last_ref_;
  set_trajectory(spec);
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
    if (last_seq_ >= 0) anchor_ = Anchor{last_u_, last_ref_};
  }
}

void Compensator::set_gains(const FeedbackGains& gains) { feedback_.set_gains(gains); }

void Compensator::start_experiment(const ExperimentSpec& spec) {
  spec.validate();
  if (!experiment_) {
    experiment_ = RunningExperiment{spec};
    return;
  }
  if (queued_ == kExperimentQueue) {
    throw ParameterError("experiment", "queue full: " + std::to_string(kExperimentQueue) +
                                           " experiments already wait behind the running one");
  }
  queue_[(queue_head_ + queued_) % kExperimentQueue] = spec;
  ++queued_;
}

void Compensator::stop_experiment() noexcept {
  queued_ = 0;
  if (!experiment_) return;
  if (!experiment_->started) {
    experiment_.reset();  // it never produced a command
    return;
  }
  experiment_->end_s = loop_time(last_seq_ + config_.lead_ticks);
}

void Compensator::reset_inverse(double y0) noexcept {
  switch (mode_) {
    case FeedforwardMode::kMem:
      // A virgin stage starts on the skeleton; one that has moved (after an experiment or a
      // mode switch) is on a branch through where it is now, and the voltage must not jump.
      if (anchor_) {
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

std::optional<CompensatorOutput> Compensator::update(const CompensatorInput& sample) noexcept {
  if (sample.seq <= last_seq_) {
    ++counters_.out_of_order;
    return std::nullopt;
  }
  ++counters_.samples;
  const std::int64_t missed = last_seq_ >= 0 ? sample.seq - last_seq_ - 1 : 0;
  counters_.gaps += static_cast<std::uint64_t>(missed);
  last_seq_ = sample.seq;

  CompensatorOutput out;
  out.sample_seq = sample.seq;
  out.seq = sample.seq + config_.lead_ticks;
  const double t_cmd = loop_time(out.seq);
  const std::size_t sample_slot = static_cast<std::size_t>(sample.seq) % kRefRing;
  const double ref_at_sample = ref_tick_[sample_slot] == sample.seq ? ref_by_tick_[sample_slot] : kNaN;
  const std::size_t cmd_slot = static_cast<std::size_t>(out.seq) % kRefRing;
  ref_tick_[cmd_slot] = out.seq;

  if (experiment_) {
    if (!experiment_->started) {
      experiment_->started = true;
      experiment_->start_s = t_cmd;
      experiment_->end_s = experiment_end_s(t_cmd, experiment_->spec);
    }
    while (t_cmd >= experiment_->end_s && queued_ > 0) {
      // Back to back: the next starts where this one ended, at a whole period (phase 0).
      const double start = experiment_->end_s;
      const ExperimentSpec& next = queue_[queue_head_];
      queue_head_ = (queue_head_ + 1) % kExperimentQueue;
      --queued_;
      experiment_ = RunningExperiment{next, true, start, experiment_end_s(start, next)};
    }
    if (t_cmd < experiment_->end_s) {
      const ExperimentSpec& e = experiment_->spec;
      out.u_V = experiment_voltage(e, t_cmd - experiment_->start_s);
      out.u_ff_V = out.u_V;
      out.y_ref_m = kNaN;
      out.error_m = kNaN;
      out.mode = FeedforwardMode::kExperiment;
      out.params_version = params_version_;
      ref_by_tick_[cmd_slot] = kNaN;
      last_u_ = out.u_V;
      feedback_.reset();
      return out;
    }
    // Back to tracking: the reference restarts, approaching it from where the stage is.
    experiment_.reset();
    trajectory_.blend_s = std::max(trajectory_.blend_s, 0.5);
    trajectory_.start_s = t_cmd + trajectory_.blend_s;
    trajectory_.hold_m = sample.y_m;
    last_ref_ = sample.y_m;
    anchor_ = Anchor{sample.u_V, sample.y_m};
    last_dir_ = 0.0;
    inverse_fresh_ = true;
  }

  const double y_ref = evaluate(trajectory_, t_cmd);
  const double step = y_ref - last_ref_;
  if (step != 0.0) {
    const double dir = step > 0.0 ? 1.0 : -1.0;
    out.reversal = last_dir_ != 0.0 && dir != last_dir_;
    last_dir_ = dir;
  }
  if (out.reversal && pending_mem_) {
    // At a reversal the inverse starts a new branch from its last point: swapping here
    // changes the slope of what follows, never the voltage already reached.
    mem_.set_params(*pending_mem_);
    params_version_ = pending_version_;
    pending_mem_.reset();
    ++counters_.params_swapped;
  }
  if (inverse_fresh_) {
    reset_inverse(y_ref);
    inverse_fresh_ = false;
    anchor_.reset();
  }

  out.y_ref_m = y_ref;
  out.u_ff_V = feedforward(y_ref);
  out.error_m = std::isfinite(ref_at_sample) ? ref_at_sample - sample.y_m : kNaN;
  if (feedback_.gains().enabled()) {
    const double dt = config_.dt_s * static_cast<double>(missed + 1);
    out.u_fb_V = std::isfinite(out.error_m) ? feedback_.update(out.error_m, out.u_ff_V, dt) : 0.0;
  }
  out.u_V = out.u_ff_V + out.u_fb_V;
  if (!std::isfinite(out.u_V)) {  // never hand a non-finite voltage on
    ++counters_.nonfinite_outputs;
    out.u_V = last_u_;
  }
  out.mode = mode_;
  out.params_version = params_version_;
  ref_by_tick_[cmd_slot] = y_ref;
  last_ref_ = y_ref;
  last_u_ = out.u_V;
  return out;
}

}  // namespace hystloop
