#pragma once
// The parameter sets on their way into the plan. A set is validated and checked when it is offered
// (Compensator::offer_model, offer_mem_params) and then waits here, with its version, for the next
// reversal of the reference, where the planner swaps it in (FeedforwardPlanner::swap_params): the
// inverse's branch restarts there, so the voltage does not jump. A later offer replaces one still
// waiting. After the swap the plan is re-anchored at the measured position (the anchor below:
// loop/feedforward_anchor.hpp), because the plan runs ahead of the samples and the reversal's
// measured position arrives after the swap was planned.
//
// A learned line may hold a set back (held_by_learning): its tables have learned the error of the
// set in use, and a new one would only be a step of the error they must learn again.

#include <cstdint>
#include <optional>

#include "loop/compensator_config.hpp"
#include "loop/feedforward_anchor.hpp"

namespace hystloop {

class ParameterExchange {
 public:
  struct Pending {
    ModelParamSet params;
    bool switch_model;       // offer_model: make it the feedforward; offer_mem_params: parameters only
    bool take_back = false;  // the set a reviewed swap replaced, going back in: not judged again
  };

  explicit ParameterExchange(const CompensatorConfig& config);

  // A validated, checked set; replaces one still waiting (a take-back too: a newer set is judged
  // as any).
  void offer(const ModelParamSet& params, bool switch_model, std::int32_t version, bool take_back = false) noexcept;
  // The mode was changed by hand: a take-back waiting would switch the model back. Dropped.
  void drop_take_back() noexcept {
    if (pending_ && pending_->take_back) pending_.reset();
  }
  bool has_pending() const noexcept { return pending_.has_value(); }
  const Pending& pending() const noexcept { return *pending_; }  // only while has_pending()
  // The waiting set changes the model a plan in `mode` follows.
  bool switches_model(FeedforwardMode mode) const noexcept;
  // The waiting set must wait on: the line learning in `mode` has taken learning.hold_params_after
  // tables under the set in use and its table is well inside learning.max_correction_m.
  bool held_by_learning(FeedforwardMode mode, const LearnerFigures& learning,
                        const LearningConfig& config) const noexcept;
  // The waiting set, whose version is in force from now on.
  Pending take() noexcept;

  std::int32_t version() const noexcept { return version_; }  // of the set in force
  // What a restarted law keeps: the version in force and the set still waiting (not the anchor:
  // the new law starts at rest).
  void carry_over(const ParameterExchange& from) noexcept;

  FeedforwardAnchor& anchor() noexcept { return anchor_; }
  const FeedforwardAnchor& anchor() const noexcept { return anchor_; }

 private:
  std::optional<Pending> pending_;
  std::int32_t pending_version_ = 0;
  std::int32_t version_ = 0;
  FeedforwardAnchor anchor_;
};

}  // namespace hystloop
