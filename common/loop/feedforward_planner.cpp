#include "loop/feedforward_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hystloop {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

FeedforwardPlanner::FeedforwardPlanner(const CompensatorConfig& config)
    : config_(config),
      mode_(config.mode),
      inverses_(config.models),
      exchange_(config),
      review_(config.swap_review, std::llround(SwapReview::kMaxWindow_s / config.dt_s) + 1, config.horizon_ticks) {
  reversals_.reset(0.0);
  set_stage(config.stage);
  counters_.stage_swaps = 0;
}

void FeedforwardPlanner::set_stage(const StageModel& stage) noexcept {
  stage_model_ = stage;
  stage_inverse_.reset();
  servo_share_.set_none();
  preview_.reset();
  preview_ticks_ = 0;
  if (stage.is_second_order()) {
    stage_inverse_.emplace(stage.second_order, config_.dt_s);  // validated by the caller
    servo_share_.set_second_order(stage.second_order);
  } else if (stage.is_linear()) {
    // Validated by the caller (StageModel::validate checks that this preview inverts it), so
    // nothing here throws; a linear stage arrives from the configuration, not per tick.
    const DiscreteLinearStage sampled = discretise(stage.linear, config_.dt_s);
    preview_ticks_ = stage_preview_ticks(sampled, stage.preview_ticks, stage.reference_bandwidth_hz);
    preview_.emplace(sampled, preview_ticks_, stage.reference_bandwidth_hz);
    servo_share_.set_linear(sampled);
    if (ahead_.size() < static_cast<std::size_t>(preview_ticks_ + 1)) {
      ahead_.resize(static_cast<std::size_t>(preview_ticks_ + 1));
    }
  }
  stage_fresh_ = true;
  ++counters_.stage_swaps;
}

void FeedforwardPlanner::carry_params_over(const FeedforwardPlanner& from) {
  inverses_.take_params_from(from.inverses_);
  exchange_.carry_over(from.exchange_);
  set_stage(from.stage_model_);
  counters_.stage_swaps = 0;  // the same stage: no swap
}

const TrajectorySpec& FeedforwardPlanner::periodic_reference() const noexcept {
  if (scan_) {
    if (const TrajectorySpec* fast = scan_->share.periodic_part()) return *fast;
  }
  return trajectory_;
}

FeedforwardPlanner::ReferencePoint FeedforwardPlanner::reference_point(const TrajectorySpec& trajectory,
                                                                       const std::optional<ScanInForce>& scan,
                                                                       double t_s) noexcept {
  const double y = evaluate(trajectory, t_s);
  if (!scan) return {y, y};
  const ScanShare::Point p = scan->share.point(t_s);
  const double sensor = y + (p.own_m - scan->base_m);
  // The decoupling's term fades in along a smoothstep (zero slope and curvature at both ends: the
  // stage's inverse differentiates it twice) over the approach, where the axis is still holding.
  double weight = 1.0;
  const double begin = scan->share.start_s() - scan->blend_s;
  if (t_s < scan->share.start_s()) {
    const double x = scan->blend_s > 0.0 ? std::clamp((t_s - begin) / scan->blend_s, 0.0, 1.0) : 0.0;
    weight = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
  }
  return {sensor, sensor + weight * (p.share_m - p.own_m)};
}

void FeedforwardPlanner::restart_learning(std::int64_t k, PeriodicLearner& learning) noexcept {
  // A scan's hold (the trajectory under it) is not periodic: without a periodic part, no learning.
  const TrajectorySpec& reference = periodic_reference();
  const auto period = period_ticks(reference, config_.dt_s);
  if (!period || !learning_room_) {
    learning.stop();
    return;
  }
  // Phase 0 a quarter period after the shape is entered (the approach before it is not
  // periodic): a new table is adopted at a period boundary, and its change is a small step of the
  // reference there, harmless where the reference moves fastest but, at a reversal, a tiny extra
  // reversal of the voltage: a minor loop the stage does not close (Coleman-Hodgdon's next branch
  // moves by ~2 alpha (f - y) du), i.e. a random offset until the next period's learning.
  const double phase0_s = reference.start_s + first_extreme_s(reference) + 0.25 / reference.frequency_hz;
  const auto k0 = static_cast<std::int64_t>(std::ceil(phase0_s / config_.dt_s - 1e-9));
  learning.restart(std::max(k, k0), *period);
}

void FeedforwardPlanner::apply_trajectory(const TrajectorySpec& given, double start_s, const ScanShare* scan) noexcept {
  TrajectorySpec spec = given;
  learner_restart_ = true;
  // The reference in force moves (a periodic shape already entered, or its approach): the new
  // approach fades it out instead of holding where it was.
  bool moving = false;
  if (!trajectory_starts_now_ && next_tick_ > 0 && counters_.planned > 0 && !in_experiment_ && !awaiting_anchor_) {
    const double t = loop_time(next_tick_);
    const ReferencePoint now = reference_at(t);
    // A scan that holds its end still carries its decoupling term (the aim is not the sensor's
    // reference): dropping it would step the inverse's target; it is faded out as a moving one.
    moving = now.aim_m != reference_at(t - config_.dt_s).aim_m || now.aim_m != now.sensor_m;
  }
  if (moving) {
    previous_trajectory_ = trajectory_;
    previous_scan_ = scan_;
    from_moving_ = true;
  }  // else a fade under way (into a hold) goes on into the new approach
  scan_.reset();
  if (scan) scan_.emplace(ScanInForce{*scan, spec.offset_m, spec.blend_s, false});
  const bool timed = !std::isnan(start_s);
  if (timed && next_tick_ >= 0 && start_s - spec.blend_s < loop_time(next_tick_)) {
    trajectory_ = spec;
    trajectory_starts_now_ = true;
    trajectory_timed_ = false;
    return;
  }
  if (timed) {
    spec.start_s = start_s;
    spec.hold_m = last_ref_;
  }
  trajectory_ = spec;
  trajectory_starts_now_ = !timed;
  trajectory_timed_ = timed;
}

double FeedforwardPlanner::nominal_slope() const noexcept {
  return inverses_.nominal_slope(model_kind_of(mode_).value_or(ModelKind::linear));
}

void FeedforwardPlanner::set_mode(FeedforwardMode mode) noexcept {
  if (mode != mode_) {
    mode_ = mode;
    // The operator's choice stands: no review of the model before it, and no take-back to it.
    review_.cancel();
    replaced_.reset();
    exchange_.drop_take_back();
    inverse_fresh_ = true;
    if (counters_.planned > 0) anchor_ = StagePoint{last_u_, last_w_, kNaN};
  }
}

void FeedforwardPlanner::reset_inverse(double y0) noexcept {
  if (const auto kind = model_kind_of(mode_)) inverses_.start(*kind, y0, anchor_);
}

double FeedforwardPlanner::feedforward(double y_ref) noexcept {
  const auto kind = model_kind_of(mode_);
  return kind ? inverses_.inverse(*kind, y_ref) : 0.0;
}

std::optional<double> FeedforwardPlanner::observe(const CompensatorInput& sample) noexcept {
  switch (ticks_.observe(sample.seq, 1)) {
    case SequenceGapDetector::Outcome::kFirst:
    case SequenceGapDetector::Outcome::kInOrder:
    case SequenceGapDetector::Outcome::kGap: break;
    default: ++counters_.out_of_order; return std::nullopt;  // late, repeated or outside the contract
  }
  ++counters_.samples;
  counters_.gaps = ticks_.missing();
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
    anchor_ = StagePoint{sample.u_V, sample.y_m, experiment_branch_u_};
    restart_reference(loop_time(next_tick_), sample.y_m);
  }
  if (exchange_.anchor().observe(sample.seq, sample.y_m, sample.u_V, next_tick_, nominal_slope())) {
    ++counters_.reanchors;
  }
  // The bridge's safe state is no tracking: a review across it says nothing.
  if (sample.safe_state) review_.not_comparable(sample.seq);
  if (review_.observe(sample.seq, sample.y_m) == SwapReview::Verdict::worse && replaced_) {
    // The set before goes back in at the next reversal, as any set does (re-anchored there), in
    // place of one still waiting: a set fitted since is no better founded than the one refused.
    ++counters_.swaps_taken_back;
    exchange_.offer(replaced_->params, /*switch_model=*/true, replaced_->version, /*take_back=*/true);
    replaced_.reset();
  }
  // Fast: half the plan's share of the slew limit per tick, where a servo along it could reach the limit.
  servo_activity_.observe(sample, config_.dt_s, 0.5 * config_.tracking_slew_V_per_s() * config_.dt_s);
  return sample.y_m - servo_share_.position_m(sample, inverses_.linear_params().gain, config_.dt_s);
}

void FeedforwardPlanner::restart_reference(double t_s, double from_m) noexcept {
  // A scan is fixed in loop time and has moved on meanwhile: it ends, and the reference approaches
  // the hold under it (where the path started).
  scan_.reset();
  trajectory_.blend_s = std::max(trajectory_.blend_s, 0.5);
  const double earliest = t_s + trajectory_.blend_s;
  // A trajectory given a start time keeps it when it is still ahead; otherwise as soon as possible.
  trajectory_.start_s = trajectory_timed_ ? std::max(trajectory_.start_s, earliest) : earliest;
  trajectory_.hold_m = from_m;
  trajectory_starts_now_ = false;
  from_moving_ = false;
  last_ref_ = from_m;
  last_w_ = from_m;
  reversals_.reset(from_m);
  inverse_fresh_ = true;
  stage_fresh_ = true;
  learner_restart_ = true;
  ref_next_ = -1;  // what was planned ahead belongs to the reference before
}

std::size_t FeedforwardPlanner::plan(std::span<CommandTick> out, PeriodicLearner* learning) noexcept {
  std::size_t n = 0;
  while (n < out.size() && next_tick_ >= 0 && next_tick_ <= plan_end_) {
    out[n++] = plan_tick(next_tick_++, learning);
    ++counters_.planned;
  }
  return n;
}

CommandTick FeedforwardPlanner::plan_tick(std::int64_t k, PeriodicLearner* learning) noexcept {
  constexpr auto kExperimentMode = static_cast<std::int8_t>(FeedforwardMode::kExperiment);
  const ExperimentQueue::Step e = experiments_.step(loop_time(k));
  if (e.active) {
    if (!in_experiment_) {
      experiment_u_.reset(e.voltage_V);
      in_experiment_ = true;
      if (learning != nullptr) learning->stop();  // an excitation is no period of the reference
    } else {
      experiment_u_.update(e.voltage_V);
    }
    // An excitation moves within the slew limit's admitted share (the bridge never has to clamp
    // it); one that starts away from where the plan is (the previous experiment's offset, or the
    // tracking voltage: a jump beyond that share) is approached at the conservative ramp rate
    // until the command meets it (within a step, or the excitation crossed the command).
    const double max_step = config_.plan_slew_fraction * config_.slew_V_per_s * config_.dt_s;
    const double ramp_step = std::min(max_step, config_.experiment_ramp_V_per_s * config_.dt_s);
    const double gap = e.voltage_V - last_u_;
    if (!approaching_ && std::abs(gap) > max_step) {
      approaching_ = true;
      approach_gap_V_ = gap;
    }
    double u = e.voltage_V;
    if (approaching_) {
      const bool met = std::abs(gap) <= ramp_step || (gap > 0.0) != (approach_gap_V_ > 0.0);
      if (met && std::abs(gap) <= max_step) {
        approaching_ = false;
      } else {
        u = last_u_ + std::copysign(std::min(ramp_step, std::abs(gap)), gap);
        approach_gap_V_ = gap;
        ++counters_.experiment_ramped;
      }
    }
    last_u_ = u;
    last_u_wanted_ = kNaN;
    review_.not_comparable(k);
    return {k, u, kNaN, exchange_.version(), kExperimentMode};
  }
  approaching_ = false;
  if (e.ended) {
    awaiting_anchor_ = true;
    anchor_tick_ = k;
    in_experiment_ = false;
    experiment_branch_u_ = experiment_u_.turning_point();
  }
  if (awaiting_anchor_) {
    last_u_wanted_ = kNaN;
    review_.not_comparable(k);
    return {k, last_u_, kNaN, exchange_.version(), static_cast<std::int8_t>(mode_)};
  }
  return tracking_tick(k, learning);
}

FeedforwardPlanner::ReferencePoint FeedforwardPlanner::reference_tick(std::int64_t k, double t,
                                                                      PeriodicLearner* learning) noexcept {
  if (trajectory_starts_now_) {
    trajectory_.start_s = t + trajectory_.blend_s;
    trajectory_.hold_m = last_ref_;
    trajectory_starts_now_ = false;
  }
  if (learner_restart_) {
    if (learning != nullptr) restart_learning(k, *learning);
    learner_restart_ = false;
  }
  // The lines are over: the raster holds its end, no period left to learn.
  if (scan_ && !scan_->lines_over && t >= scan_->share.end_s()) {
    scan_->lines_over = true;
    if (scan_->share.periodic_part() && learning != nullptr) learning->stop();
  }
  ReferencePoint ref = reference_at(t);
  if (from_moving_) {
    // A new reference while the old one moves: the approach starts from the old one, faded out
    // along a smoothstep (zero slope and curvature at both ends), so that neither its velocity
    // nor its acceleration steps (a step the stage's inverse would turn into a voltage jump).
    const double begin = trajectory_.start_s - trajectory_.blend_s;
    const double length = trajectory_.blend_s + first_extreme_s(trajectory_);
    const double s = length > 0.0 ? (t - begin) / length : 1.0;
    if (s >= 1.0) {
      from_moving_ = false;
    } else if (s > 0.0) {
      const double w = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
      const ReferencePoint old = previous_reference_at(t);
      ref = {(1.0 - w) * old.sensor_m + w * ref.sensor_m, (1.0 - w) * old.aim_m + w * ref.aim_m};
    } else {
      ref = previous_reference_at(t);
    }
  }
  return ref;
}

void FeedforwardPlanner::restart_inverse(double y0) noexcept {
  reset_inverse(y0);
  inverse_fresh_ = false;
  anchor_.reset();
  FeedforwardAnchor& anchor = exchange_.anchor();
  if (anchor.measuring()) ++counters_.reanchors_skipped;
  anchor.reset(0.0);
  u_prev_rev_ = last_u_;
}

CommandTick FeedforwardPlanner::tracking_tick(std::int64_t k, PeriodicLearner* learning) noexcept {
  if (preview_) return preview_tick(k, learning);
  const double t = loop_time(k);
  const ReferencePoint ref = reference_tick(k, t, learning);
  // The sensor's reference (the servo's, the learning's, the anchor's) and the one the inverses aim
  // the axis's own displacement at: equal but during a decoupled scan.
  const double y_ref = ref.sensor_m;
  const double y_aim = ref.aim_m;
  FeedforwardAnchor& anchor = exchange_.anchor();
  const bool reversal = reversals_.update(y_aim) == ReversalDetector::Event::kReversal;
  if (reversal) at_reversal(k, learning);
  if (inverse_fresh_) restart_inverse(y_aim);
  // The reference the inverse aims at: with what the learning has found this point of the period
  // needs, and, for hysteresis then stage, through the stage's inverse first.
  const double correction = learning != nullptr ? learning->correction(k, y_ref) : 0.0;
  const double r = y_aim + correction;
  const bool stage_first = stage_inverse_ && stage_model_.order == BanningOrder::kHysteresisThenStage;
  if (stage_first && stage_fresh_) {
    stage_inverse_->reset(r);
    stage_fresh_ = false;
  }
  const double w_ref = stage_first ? stage_inverse_->step(r) : r;
  shift_m_ = anchor.y_offset(k);
  const double shift_V = anchor.u_offset(k);
  const double y_model = w_ref - shift_m_;
  double u = feedforward(y_model) + shift_V;
  if (stage_inverse_ && !stage_first) {  // stage then hysteresis: the stage's input from its output
    if (stage_fresh_) {
      stage_inverse_->reset(u);
      stage_fresh_ = false;
    }
    u = stage_inverse_->step(u);
  }
  last_ref_ = y_ref;
  return command(k, u, y_ref, correction, w_ref, shift_V, reversal, learning);
}

CommandTick FeedforwardPlanner::command(std::int64_t k, double u, double y_ref, double correction, double w_ref,
                                        double shift_V, bool reversal, PeriodicLearner* learning) noexcept {
  FeedforwardAnchor& anchor = exchange_.anchor();
  if (!std::isfinite(u)) {  // never hand a non-finite voltage on
    ++counters_.nonfinite_outputs;
    u = last_u_;
  }
  // What the plan needs, before any clamp (the dry runs of take_trajectory read it).
  // (against the previous tick's unclamped value: after a clamp the distance to the clamped
  // voltage would grow tick by tick and read as a rate the plan never asked for)
  const double rate = std::abs(u - (std::isnan(last_u_wanted_) ? last_u_ : last_u_wanted_)) / config_.dt_s;
  last_u_wanted_ = u;
  extent_.u_min_V = std::min(extent_.u_min_V, u);
  extent_.u_max_V = std::max(extent_.u_max_V, u);
  extent_.rate_max_V_per_s = std::max(extent_.rate_max_V_per_s, rate);
  ++extent_.ticks;
  // A learned correction is admitted only beside a line that leaves room for it (take_trajectory),
  // so where the plan with it would leave the limits, it is the learning's excess: held back,
  // counted as such (not a clamp of the line) and not learned from at that tick.
  const bool learned = correction != 0.0;
  bool held = false;  // a tick both limits hold back is one tick held
  const auto limited = [&](std::uint64_t& clamp_count) {
    if (!learned) {
      ++clamp_count;
    } else if (!held) {
      held = true;
      ++counters_.learning_held;
      learning->hold(k);  // a correction came from it: not null
    }
  };
  // A learned correction takes only what the servo's recent peaks leave of the range (on the side
  // it pushes towards) and of the plan's share of the slew limit (ServoActivity): the bridge clamps
  // the sum, not the feedforward. The slew held to never below half that share: a servo stepping
  // more than that along the feedforward is the bridge's to clamp.
  double u_lo = config_.u_min_V, u_hi = config_.u_max_V;
  double max_step = config_.tracking_slew_V_per_s() * config_.dt_s;
  if (learned) {
    if (correction > 0.0) u_hi = std::max(u_lo, u_hi - servo_activity_.above_peak_V());
    if (correction < 0.0) u_lo = std::min(u_hi, u_lo + servo_activity_.below_peak_V());
    const double left =
        config_.plan_slew_fraction * config_.slew_V_per_s * config_.dt_s - servo_activity_.step_along_peak_V();
    max_step = std::clamp(left, 0.5 * max_step, max_step);
  }
  if (u < u_lo || u > u_hi) {
    limited(counters_.u_clamped);
    u = std::clamp(u, u_lo, u_hi);
  }
  // The plan keeps within the share of the slew limit a trajectory was admitted at (the rest is
  // the servo's, beside the sensor); what learning or a swap would ask beyond it is held back here
  // and counted, not clamped by the bridge behind the servo's back.
  if (std::abs(u - last_u_) > max_step) {
    limited(counters_.u_slew_clamped);
    u = last_u_ + std::copysign(max_step, u - last_u_);
  }
  // The anchor compares the measured position with the reference the model was asked for (not
  // the learned correction: what the learning adds is meant to make y follow y_ref).
  anchor.planned(k, y_ref - shift_m_, u - shift_V, reversal);
  review_.planned(k, y_ref, !learned && comparable_reference(k));
  last_w_ = w_ref;
  last_u_ = u;
  return {k, u, y_ref, exchange_.version(), static_cast<std::int8_t>(mode_)};
}

}  // namespace hystloop
