#include "reident/reident_core.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/errors.hpp"

namespace hystloop {

namespace {
// Checked before the worker thread starts (the members after axis_).
std::size_t block_axis(int axis) {
  if (axis < 0 || axis >= sensor_block_t::MAX_AXES) {
    throw ParameterError("reidentifier.axis", "must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
  }
  return static_cast<std::size_t>(axis);
}
}  // namespace

ReidentCore::ReidentCore(const ReidentOptions& options, std::string own_source, bool start_thread,
                         RefitWorker::OnEvaluated on_evaluated)
    : options_(options),
      axis_(block_axis(options.axis)),
      estimator_(options.estimator, options.initial),
      stage_removal_(options.stage, 1.0 / options.rate_hz),
      in_use_(options.initial, std::move(own_source), new_publisher_id()),
      worker_(options.estimator, estimator_.make_window(), start_thread, std::move(on_evaluated), options.plausibility),
      period_us_(std::llround(options.refit_period_s * 1e6)),
      stale_after_us_(std::llround(options.stale_after_s * 1e6)) {}

bool ReidentCore::on_sensor_block(const sensor_block_t& block, std::int64_t now_us) noexcept {
  if (axis_ >= axes_of(block)) {
    // Another axis in our place would be fitted as ours: refused, and its ticks are no gap (the
    // window is poisoned, so no refit straddles the hole).
    counters_.add(ReidentCounter::sensor_blocks_wrong_axes);
    on_refused_block(block.n_ticks, now_us);
    return false;
  }
  for_each_tick(
      block, [this, now_us](const SensorTick& tick) { on_sample(tick, now_us); }, axis_);
  return true;
}

void ReidentCore::on_sample(const SensorTick& tick, std::int64_t now_us) noexcept {
  last_sample_us_ = now_us;
  const std::int64_t seq = tick.seq;
  const std::uint64_t missing_before = ticks_.missing();
  const SequenceGapDetector::Outcome step = ticks_.observe(seq, 1);
  // The stage's removal looks at neighbouring samples: any break hands out what it holds (flush).
  if (step != SequenceGapDetector::Outcome::kInOrder) flush_stage_removal();
  if (step == SequenceGapDetector::Outcome::kGap) {
    // Ticks refused on the wire since the last one were not lost: they are no gap.
    const auto jumped = static_cast<std::int64_t>(ticks_.missing() - missing_before);
    if (const std::int64_t missing = jumped - refused_since_last_; missing > 0) {
      counters_.add(ReidentCounter::seq_gaps);
      counters_.add(ReidentCounter::samples_missed, static_cast<std::uint64_t>(missing));
    }
  } else if (step == SequenceGapDetector::Outcome::kRestart || step == SequenceGapDetector::Outcome::kDuplicate) {
    counters_.add(ReidentCounter::seq_restarts);  // the numbering went back or repeated a tick
  }
  refused_since_last_ = 0;
  in_use_.on_sample(seq);
  if (std::isfinite(tick.y_ref_m) && std::isfinite(last_ref_m_) && tick.y_ref_m != last_ref_m_) {
    moving_ref_fed_ = estimator_.samples_fed() + 1;  // this tick, once fed
  }
  last_ref_m_ = tick.y_ref_m;
  if ((tick.flags & sensor_block_t::SAFE_STATE) != 0) {
    counters_.add(ReidentCounter::skipped_safe_state);
    flush_stage_removal();
    return;
  }
  if ((tick.flags & sensor_block_t::SENSOR_FAULT) != 0) {
    counters_.add(ReidentCounter::skipped_sensor_fault);
    flush_stage_removal();
    return;
  }
  HysteresisSample ready[2];
  const std::size_t n = stage_removal_.feed(tick.u_V, tick.y_m, ready);
  for (std::size_t i = 0; i < n; ++i) estimator_.feed(ready[i].u, ready[i].y);
}

void ReidentCore::flush_stage_removal() noexcept {
  if (const auto held = stage_removal_.reset()) estimator_.feed(held->u, held->y);
}

void ReidentCore::on_refused_block(std::int64_t ticks, std::int64_t now_us) noexcept {
  // The estimator counts the marker as non-finite: one per block is enough to poison the window.
  last_sample_us_ = now_us;
  refused_since_last_ += ticks > 0 ? ticks : 1;
  flush_stage_removal();
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  estimator_.feed(kNaN, kNaN);
}

void ReidentCore::on_command_block(const command_block_t& block) noexcept {
  if (axis_ >= axes_of(block)) return;
  for_each_tick(
      block, [this](const CommandTick& tick) { in_use_.on_command(tick.seq, tick.params_version); }, axis_);
}

ParamsOffer ReidentCore::on_params(int axis, const MemParams& params, std::int32_t version, std::int64_t publisher_id,
                                   bool valid, std::string_view source) noexcept {
  if (axis != options_.axis) {
    counters_.add(ReidentCounter::params_other_axis);
    return ParamsOffer::other_axis;
  }
  return on_params(params, version, publisher_id, valid, source);
}

ParamsOffer ReidentCore::on_params(const MemParams& params, std::int32_t version, std::int64_t publisher_id, bool valid,
                                   std::string_view source) noexcept {
  if (valid && publisher_id != in_use_.own_publisher_id() && implausible(params)) {
    // A set the compensator would refuse as not this stage's must not become the set refits are
    // judged against: offered as invalid, so that its version still counts as seen.
    in_use_.offer(params, version, publisher_id, /*valid=*/false, source);
    counters_.add(ReidentCounter::params_implausible);
    return ParamsOffer::invalid;
  }
  const ParamsOffer offer = in_use_.offer(params, version, publisher_id, valid, source);
  switch (offer) {
    case ParamsOffer::adopted: counters_.add(ReidentCounter::params_adopted); break;
    case ParamsOffer::echo: counters_.add(ReidentCounter::params_echo); break;
    case ParamsOffer::stale: counters_.add(ReidentCounter::params_stale); break;
    case ParamsOffer::invalid: counters_.add(ReidentCounter::params_invalid); break;
    // forged: counted by ParamsInUse (forged_sets; params_forged on HX_STATUS); other_axis is
    // on_params(axis, ...)'s answer, never ParamsInUse's.
    case ParamsOffer::forged:
    case ParamsOffer::other_axis: break;
  }
  return offer;
}

bool ReidentCore::implausible(const MemParams& params) noexcept {
  try {
    params.validate();
  } catch (...) {
    return false;  // outside MEM's domain: params_invalid, as ParamsInUse refuses it
  }
  try {
    ModelParamSet set;
    set.mem = params;
    require_plausible(set, options_.plausibility);
    return false;
  } catch (const ParameterError& e) {
    try {
      implausible_reason_ = e.what();
    } catch (...) {  // out of memory: the count still says it
    }
  } catch (...) {
  }
  return true;
}

bool ReidentCore::on_new_reference() noexcept {
  // The window: the last window_samples fed, and none before the last restart.
  const std::uint64_t fed = estimator_.samples_fed();
  const std::uint64_t first =
      fed - std::min<std::uint64_t>(options_.estimator.window_samples, estimator_.samples_since_restart());
  if (moving_ref_fed_ <= first) return false;  // no tick of a moving reference in it
  flush_stage_removal();
  estimator_.restart_window();
  moving_ref_fed_ = 0;
  counters_.add(ReidentCounter::window_restarts);
  return true;
}

RefitDecision ReidentCore::poll(std::int64_t now_us) noexcept {
  RefitDecision d;
  if (worker_.done()) {
    d = decide(worker_.result());
    worker_.release();
  }
  const std::uint64_t fed = estimator_.samples_fed();
  if (mem_refits_ && worker_.idle() && now_us >= next_refit_us_ &&
      estimator_.samples_since_restart() >= options_.estimator.window_samples && fed != fed_at_last_snapshot_) {
    estimator_.snapshot(worker_.job_window());               // no allocation: the worker's window is preallocated
    worker_.submit(in_use_.params(), in_use_.generation());  // "version": which set in use it was judged against
    counters_.add(ReidentCounter::refits_attempted);
    fed_at_last_snapshot_ = fed;
    next_refit_us_ = now_us + period_us_;
  }
  return d;
}

RefitDecision ReidentCore::decide(const RefitResult& r) noexcept {
  const MemRefitOutcome& o = r.outcome;
  RefitDecision d;
  d.status = o.status;
  d.fitted = o.fit.samples_used > 0;
  d.candidate = o.candidate;
  d.holdout_rms_candidate_m = o.holdout_rms_candidate_m;
  d.holdout_rms_in_use_m = o.holdout_rms_in_use_m;
  d.fit_residual_rms_m = o.fit.residual_rms_m;
  d.samples_used = o.fit.samples_used;
  d.window_samples = r.window_samples;
  d.duration_s = r.duration_s;
  last_refit_s_ = r.duration_s;
  refit_time_.add(std::llround(r.duration_s * 1e9));
  poisoned_streak_ = o.status == FitStatus::poisoned_window ? poisoned_streak_ + 1 : 0;

  if (!o.accepted) {
    // An "accepted" outcome always has status ok; anything else is a refusal with its reason.
    counters_.add_rejected(o.status);
    if (r.implausible) counters_.add(ReidentCounter::refits_implausible);
    d.kind = RefitDecision::Kind::refused;
    return d;
  }
  // A refit that finished after the model choice switched away from MEM, or whose window the new
  // reference since has made another's, is not published.
  if (o.judged_against_version != in_use_.generation() || !mem_refits_ ||
      estimator_.restarted_since(fed_at_last_snapshot_)) {
    counters_.add(ReidentCounter::refits_superseded);
    d.kind = RefitDecision::Kind::superseded;
    return d;
  }
  if (held_) {
    counters_.add(ReidentCounter::refits_held);
    d.kind = RefitDecision::Kind::held;
    return d;
  }
  d.version = in_use_.adopt_own(o.candidate);
  counters_.add(ReidentCounter::refits_accepted);
  d.kind = RefitDecision::Kind::accepted;
  return d;
}

bool ReidentCore::stale(std::int64_t now_us) const noexcept {
  return last_sample_us_ < 0 || now_us - last_sample_us_ > stale_after_us_;
}

bool ReidentCore::poisoned() const noexcept { return poisoned_streak_ >= options_.degraded_after_poisoned; }

double ReidentCore::seconds_since_sample(std::int64_t now_us) const noexcept {
  return last_sample_us_ < 0 ? std::numeric_limits<double>::infinity()
                             : static_cast<double>(now_us - last_sample_us_) * 1e-6;
}

const ReidentCounters& ReidentCore::counters() noexcept {
  counters_.set(ReidentCounter::samples_fed, estimator_.samples_fed());
  counters_.set(ReidentCounter::non_finite, estimator_.non_finite_samples());
  counters_.set(ReidentCounter::dropouts, estimator_.dropouts());
  counters_.set(ReidentCounter::command_versions_dropped, in_use_.command_versions_dropped());
  return counters_;
}

void ReidentCore::reset_refit_time() noexcept { refit_time_.reset(); }

}  // namespace hystloop
