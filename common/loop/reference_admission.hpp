#pragma once
// Whether the plan can follow a reference before it is taken. A trajectory, an axis's share of a
// path, or a parameter set under the line in force is checked by a dry run: a copy of the planner
// (loop/feedforward_planner.hpp, without the learning) plans it, and what its feedforward needs
// (PlanExtent) must stay inside the actuator's range and tracking_slew_fraction() of its slew limit.
// Otherwise it is refused (ParameterError) naming the limit and the largest feasible amplitude and
// frequency, or shaped to feasibility when asked. A triangle's corners are rounded; with corner_s 0
// the shortest rounding the limits allow is chosen by the same dry run. Nothing here is on the
// per-sample path.

#include <string>

#include "loop/feedforward_planner.hpp"

namespace hystloop {

class ReferenceAdmission {
 public:
  // A dry run covers the approach and this many periods: both corners and the branch after each.
  static constexpr double kDryRunPeriods = 1.25;
  // A path is checked whole before it is taken: one ending further ahead is refused.
  static constexpr std::int64_t kDryRunMaxTicks = 200'000;
  // Learning needs room beside a line: a line whose feedforward needs more of the slew limit than
  // this is tracked without (reached only where compensator.servo_slew_reserve is set below 2 %).
  static constexpr double kLearningSlewShare = 0.97;

  explicit ReferenceAdmission(const FeedforwardPlanner& planner) : planner_(planner) {}

  // How `spec` is to be taken from where the plan is: its corner chosen, shaped when it asks and
  // must be, its extent; throws ParameterError when it is infeasible (counted by the caller).
  TrajectoryVerdict admit_trajectory(TrajectorySpec spec, double start_s, bool learning_enabled) const;
  // A path's share: every check and the dry run over the approach and the whole path.
  PlanExtent admit_scan(const ScanShare& share, double blend_s) const;
  // Throws when `candidate` swapped in would take the line or path in force beyond the plan's share
  // of the slew limit (nothing to check without one, or for a model not in use).
  void check_line_under(const ModelParamSet& candidate, bool switch_model) const;
  // The line leaves room for learning's corrections.
  bool leaves_room_for_learning(const PlanExtent& e) const noexcept;

  PlanExtent dry_run(const TrajectorySpec& spec, double start_s, const ScanShare* scan = nullptr) const;
  PlanExtent dry_run_periodic(const TrajectorySpec& spec) const;

 private:
  bool feasible(const PlanExtent& e) const noexcept;
  double choose_corner(const TrajectorySpec& spec, std::string& note) const;
  double feasible_amplitude(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const;
  std::string infeasibility(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const;
  std::string limits_left(const PlanExtent& e) const;  // which limit e leaves, and by how much
  const CompensatorConfig& config() const noexcept { return planner_.config(); }

  const FeedforwardPlanner& planner_;
};

// The hold a path's share starts from (the axis's own reference at the path's start).
TrajectorySpec scan_hold(const ScanShare& share, double blend_s);

}  // namespace hystloop
