// The plan's preview of a linear stage (FeedforwardPlanner, loop/feedforward_planner.hpp): the
// reference is planned preview_ticks ahead of the commands, each tick's learned correction with it,
// and fed to the stage's stable inverse over that preview (models/preview_inverse.hpp), whose
// output for a tick arrives preview_ticks after the tick's reference went in. The hysteresis
// model's inverse then turns that output into the tick's voltage as for any stage.
#include "loop/feedforward_planner.hpp"

namespace hystloop {

void FeedforwardPlanner::plan_reference(std::int64_t j, PeriodicLearner* learning, bool start_inverse) noexcept {
  const ReferencePoint ref = reference_tick(j, loop_time(j), learning);
  PlannedReference& p = ahead(j);
  p.y_ref = ref.sensor_m;
  p.y_aim = ref.aim_m;
  p.reversal = reversals_.update(ref.aim_m) == ReversalDetector::Event::kReversal;
  p.correction = learning != nullptr ? learning->correction(j, ref.sensor_m) : 0.0;
  p.w = p.y_aim;  // until the inverse's output for this tick arrives, preview_ticks later
  last_ref_ = ref.sensor_m;
  const double r = p.y_aim + p.correction;
  if (start_inverse) preview_->reset(r);
  // The inverse's output is the stage input of the tick preview_ticks back.
  const double w = preview_->step(r);
  if (j - preview_ticks_ >= 0) ahead(j - preview_ticks_).w = w;
}

CommandTick FeedforwardPlanner::preview_tick(std::int64_t k, PeriodicLearner* learning) noexcept {
  bool start_inverse = false;
  if (ref_next_ < k) {
    // The reference side starts at this tick (a new reference, the first, or the plan fell behind
    // the bridge): the inverse at rest at its first point, its outputs before this tick unused.
    ref_next_ = k;
    start_inverse = true;
  } else if (stage_fresh_ && ref_next_ == k) {
    start_inverse = true;  // a stage without preview: nothing planned ahead to feed again
  } else if (stage_fresh_) {
    // A new stage under a reference already planned ahead: the inverse restarted at rest and fed
    // what was planned, so that its output reaches this tick again.
    preview_->reset(ahead(k).y_aim + ahead(k).correction);
    for (std::int64_t j = k; j < ref_next_; ++j) {
      const double w = preview_->step(ahead(j).y_aim + ahead(j).correction);
      if (j - preview_ticks_ >= k) ahead(j - preview_ticks_).w = w;
    }
  }
  stage_fresh_ = false;
  for (; ref_next_ <= k + preview_ticks_; ++ref_next_) {
    plan_reference(ref_next_, learning, start_inverse);
    start_inverse = false;
  }
  const PlannedReference p = ahead(k);
  if (p.reversal) at_reversal(k, learning);
  if (inverse_fresh_) restart_inverse(p.w);
  FeedforwardAnchor& anchor = exchange_.anchor();
  shift_m_ = anchor.y_offset(k);
  const double shift_V = anchor.u_offset(k);
  const double u = feedforward(p.w - shift_m_) + shift_V;
  return command(k, u, p.y_ref, p.correction, p.w, shift_V, p.reversal, learning);
}

}  // namespace hystloop
