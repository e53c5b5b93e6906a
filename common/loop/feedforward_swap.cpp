// The parameter sets' way into the plan (FeedforwardPlanner, loop/feedforward_planner.hpp): a
// waiting set swapped in at a reversal of the reference (unless learning holds it), the inverse
// restarted there without a step, the re-anchoring started; and the review of that swap
// (loop/swap_review.hpp), which the planner's observe() may answer with a take-back.
#include "loop/feedforward_planner.hpp"

namespace hystloop {

void FeedforwardPlanner::at_reversal(std::int64_t k, PeriodicLearner* learning) noexcept {
  ++counters_.reversals;
  const bool held = learning != nullptr && exchange_.held_by_learning(mode_, learning->figures(), config_.learning);
  if (exchange_.has_pending() && !held) swap_params(k, learning);
  u_prev_rev_ = last_u_ - exchange_.anchor().u_offset(k);
}

double FeedforwardPlanner::restart_at_reversal(FeedforwardMode mode, double u_rev) noexcept {
  const double w = last_w_ - shift_m_;
  const auto kind = model_kind_of(mode);
  return kind ? inverses_.restart_at_reversal(*kind, u_prev_rev_, u_rev, w) : w;
}

void FeedforwardPlanner::swap_params(std::int64_t k, PeriodicLearner* learning) noexcept {
  const bool switching = exchange_.switches_model(mode_);
  // What the set replaces, for a review to take back (the model in force and, when the set brings
  // one, the stage).
  Replaced before{{}, exchange_.version()};
  inverses_.get_params(before.params);
  before.params.kind = model_kind_of(mode_).value_or(ModelKind::mem);
  const ParameterExchange::Pending taken = exchange_.take();
  const ModelParamSet& p = taken.params;
  if (p.stage) before.params.stage = stage_model_;
  // A set for a model not in use that brings a stage changes what the line runs on.
  if (p.stage && !(switching || mode_of(p.kind) == mode_)) review_.not_comparable(k);
  const FeedforwardMode to = mode_of(p.kind);
  const bool in_use = switching || to == mode_;
  FeedforwardAnchor& anchor = exchange_.anchor();
  const double u_shift = anchor.u_offset(k);
  const double u_rev = last_u_ - u_shift;  // this reversal, in the model's coordinates
  inverses_.set_params(p);
  if (p.stage) set_stage(*p.stage);  // at a reversal the stage is nearly at rest: restart it there
  ++counters_.params_swapped;
  if (!in_use) return;
  // A take-back restores a set the line tracked better under: not judged again (no back and forth).
  if (review_.swapped(k, review_span(), !taken.take_back)) {
    ++counters_.swaps_reviewed;
    replaced_ = before;
  }
  if (switching) {
    mode_ = to;
    ++counters_.model_switches;
  }
  // A line learning under the old set that has no table yet: what it has observed is the old
  // set's error, which its first table would carry over to the new one. It learns from here.
  if (learning != nullptr && learning->figures().active && learning->figures().tables_this_line == 0) {
    learning->reset();
  } else if (learning != nullptr) {
    learning->params_swapped(k);  // under a table: the swap's step is no divergence of the learning
  }
  // At a reversal the inverse starts a new branch from its last point: new parameters change
  // the slope of what follows, never the voltage already reached. MEM remembers nothing else;
  // the others restart at this reversal, and the offset takes up where their output is there.
  if (switching || mode_ != FeedforwardMode::kMem) {
    anchor.reset(last_w_ - restart_at_reversal(mode_, u_rev), u_shift);
  }
  if (mode_ == FeedforwardMode::kLinear) {
    // A line has no branch to anchor: its fitted offset puts it through the middle of the loop,
    // where anchoring it at a reversal would put it at the loop's edge. Ramp back to that.
    anchor.ramp_to(0.0, u_shift, k, inverses_.linear_params().gain);
  } else {
    anchor.start_measuring(k);
  }
}

bool FeedforwardPlanner::comparable_reference(std::int64_t k) const noexcept {
  if (scan_ || trajectory_starts_now_ || from_moving_ || !periodic(trajectory_)) return false;
  return loop_time(k) >= trajectory_.start_s + first_extreme_s(trajectory_) + 1.0 / trajectory_.frequency_hz;
}

SwapReviewSpan FeedforwardPlanner::review_span() const noexcept {
  if (!periodic(trajectory_) || scan_) return {};
  return swap_review_span(1.0 / trajectory_.frequency_hz, config_.dt_s, config_.horizon_ticks + preview_ticks_,
                          config_.reanchor_ramp_ticks);
}

}  // namespace hystloop
