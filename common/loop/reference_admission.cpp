#include "loop/reference_admission.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace hystloop {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// A triangle's corners are rounded over at most this share of the period each (the rest of the
// line is straight: what a raster scan uses).
constexpr double kMaxCornerShare = 0.125;

std::string si(double value, const char* unit) { return number_text(value, 3) + " " + unit; }
}  // namespace

// The planner's preparations for a dry run, beside the dry runs that use them.
void FeedforwardPlanner::prepare_dry_run() noexcept {
  const std::int64_t k = std::max<std::int64_t>(next_tick_, 0);
  experiments_.stop(loop_time(k));
  if (awaiting_anchor_ || in_experiment_) {  // the stage is about where the plan left it
    awaiting_anchor_ = false;
    in_experiment_ = false;
    restart_reference(loop_time(k), last_ref_);
  }
}

void FeedforwardPlanner::enter_periodic_at_rest(const TrajectorySpec& spec) noexcept {
  const std::int64_t k = std::max<std::int64_t>(next_tick_, 0);
  experiments_.stop(loop_time(k));
  awaiting_anchor_ = false;
  in_experiment_ = false;
  TrajectorySpec t = spec;
  t.hold_m = last_ref_;
  t.start_s = 0.0;
  const double enter = first_extreme_s(t);
  restart_reference(loop_time(k), evaluate_shape(t, enter));
  t.blend_s = 0.0;
  t.start_s = loop_time(k) - enter;  // the shape's tau at tick k is `enter`
  t.hold_m = last_ref_;
  trajectory_ = t;
  trajectory_starts_now_ = false;
  trajectory_timed_ = true;
}

void FeedforwardPlanner::begin_extent() noexcept {
  extent_ = PlanExtent{kInf, -kInf, 0.0, 0};
  last_u_wanted_ = std::numeric_limits<double>::quiet_NaN();
}

void FeedforwardPlanner::swap_in_now(const ModelParamSet& params, bool switch_model) noexcept {
  exchange_.offer(params, switch_model, exchange_.version());
  swap_params(next_tick_, nullptr);
}

TrajectorySpec scan_hold(const ScanShare& share, double blend_s) {
  TrajectorySpec hold;
  hold.shape = TrajectoryShape::kHold;
  hold.offset_m = share.point(share.start_s()).own_m;
  hold.blend_s = blend_s;
  return hold;
}

bool ReferenceAdmission::leaves_room_for_learning(const PlanExtent& e) const noexcept {
  return e.rate_max_V_per_s <= kLearningSlewShare * config().slew_V_per_s;
}

TrajectoryVerdict ReferenceAdmission::admit_trajectory(TrajectorySpec spec, double start_s,
                                                       bool learning_enabled) const {
  TrajectoryVerdict v;
  if (spec.shape == TrajectoryShape::kTriangle && spec.corner_s == 0.0) spec.corner_s = choose_corner(spec, v.note);
  PlanExtent e = dry_run(spec, start_s);
  if (!feasible(e)) {
    if (!spec.shape_if_infeasible || !periodic(spec))
      throw ParameterError("trajectory", infeasibility(spec, start_s, e));
    const double a = feasible_amplitude(spec, start_s, e);
    if (!(std::abs(a) > 0.0)) {
      throw ParameterError("trajectory", infeasibility(spec, start_s, e) + "; no amplitude is feasible");
    }
    if (!v.note.empty()) v.note += "; ";
    v.note += "amplitude " + si(spec.amplitude_m * 1e6, "um") + " scaled to " + si(a * 1e6, "um") +
              " to stay inside the actuator's limits";
    spec.amplitude_m = a;
    e = dry_run(spec, start_s);
    v.shaped = true;
  }
  v.extent = e;
  // Learning needs room beside the line: its corrections and the servo share what the line leaves
  // of the slew limit. A line using more than kLearningSlewShare of it is tracked without
  // (measured: at 98 % a 200 Hz line clamps on 2 % of its ticks with learning and gains nothing).
  if (!leaves_room_for_learning(e) && periodic(spec) && learning_enabled) {
    if (!v.note.empty()) v.note += "; ";
    v.note += "learning off for it: the line needs " + si(100.0 * e.rate_max_V_per_s / config().slew_V_per_s, "%") +
              " of the slew limit, no room for corrections";
  }
  const std::int64_t next = planner_.next_tick();
  v.started = !(!std::isnan(start_s) && next >= 0 && start_s - spec.blend_s < planner_.loop_time(next));
  v.spec = spec;
  return v;
}

PlanExtent ReferenceAdmission::dry_run(const TrajectorySpec& spec, double start_s, const ScanShare* scan) const {
  FeedforwardPlanner c = planner_;  // off the per-sample path: a copy plans what the planner would
  c.prepare_dry_run();
  std::int64_t k = std::max<std::int64_t>(c.next_tick(), 0);
  c.apply_trajectory(spec, start_s, scan);
  c.begin_extent();
  // Through the approach and what shows what the reference needs: a scan's whole path, a periodic
  // shape's first periods, a point list's points.
  double until_s = 0.0;
  if (scan != nullptr) {
    until_s = scan->end_s() + 0.01;
  } else {
    TrajectorySpec from_here = spec;
    from_here.hold_m = c.last_ref();  // where the approach starts decides where the shape is entered
    const double t0 = (c.trajectory_starts_now() ? c.loop_time(k) + spec.blend_s : c.trajectory().start_s) +
                      first_extreme_s(from_here);
    double span = 0.01;
    if (periodic(spec)) span = kDryRunPeriods / spec.frequency_hz;
    if (spec.shape == TrajectoryShape::kPoints && spec.n_points > 0) span = spec.points_t_s[spec.n_points - 1] + 0.01;
    until_s = t0 + span;
  }
  const double dt = config().dt_s;
  const std::int64_t end = std::min(k + kDryRunMaxTicks, static_cast<std::int64_t>(std::ceil(until_s / dt)));
  for (; k <= end; ++k) c.plan_tick(k, nullptr);
  return c.extent();
}

PlanExtent ReferenceAdmission::admit_scan(const ScanShare& share, double blend_s) const {
  const double dt = config().dt_s;
  const double next_s = planner_.loop_time(std::max<std::int64_t>(planner_.next_tick(), 0));
  if (planner_.in_experiment() || planner_.experiment_running() || planner_.experiments_queued() > 0) {
    throw ParameterError("scan",
                         "an identification experiment is running or queued: its end restarts the "
                         "reference, which would leave this axis behind the path the others follow");
  }
  if (share.end_s() - next_s > static_cast<double>(kDryRunMaxTicks) * dt) {
    throw ParameterError("scan", "ends " + si(share.end_s() - next_s, "s") +
                                     " of loop time from now; a path is checked whole before it is taken, at "
                                     "most " +
                                     si(static_cast<double>(kDryRunMaxTicks) * dt, "s") + " ahead");
  }
  if (share.start_s() - blend_s < next_s) {
    throw ParameterError("scan.start_s", "must leave the approach (" + si(blend_s, "s") + ") before it: starts at " +
                                             si(share.start_s(), "s") + ", the next tick not yet planned is at " +
                                             si(next_s, "s") + " (loop time)");
  }
  const PlanExtent e = dry_run(scan_hold(share, blend_s), share.start_s(), &share);  // the approach and the path
  if (!feasible(e))
    throw ParameterError("scan", "axis " + std::string(axis_name(share.axis())) + ": " + limits_left(e));
  return e;
}

PlanExtent ReferenceAdmission::dry_run_periodic(const TrajectorySpec& spec) const {
  // As if the plan were already at the point where the shape is entered, at rest: no approach to
  // plan (a search over corners or amplitudes would otherwise plan the same approach each time).
  FeedforwardPlanner c = planner_;
  std::int64_t k = std::max<std::int64_t>(c.next_tick(), 0);
  c.enter_periodic_at_rest(spec);
  // A period to settle (the jump to the entry and the step in acceleration there ring the stage's
  // inverse, which the real approach avoids), then what the periods need.
  const auto period = static_cast<std::int64_t>(std::ceil(1.0 / (spec.frequency_hz * config().dt_s)));
  for (const std::int64_t settle_end = k + period; k < settle_end; ++k) c.plan_tick(k, nullptr);
  c.begin_extent();
  const std::int64_t end = k + static_cast<std::int64_t>(std::ceil(kDryRunPeriods * static_cast<double>(period)));
  for (; k <= end; ++k) c.plan_tick(k, nullptr);
  return c.extent();
}

bool ReferenceAdmission::feasible(const PlanExtent& e) const noexcept {
  if (e.ticks == 0) return true;
  return e.rate_max_V_per_s <= config().tracking_slew_V_per_s() && e.u_min_V >= config().u_min_V &&
         e.u_max_V <= config().u_max_V;
}

double ReferenceAdmission::choose_corner(const TrajectorySpec& spec, std::string& note) const {
  // The shortest rounding the limits allow. A sharp corner asks the inverse for a voltage rate
  // that only the slope of the branch just after the reversal bounds (with the stage's inverse,
  // for an infinite one); a long one makes the straight line steeper (its slope is
  // 2A / (T/2 - tau (1 - 2/pi))). So the feasible corners are a band, found on a grid of dry runs
  // (without the approach) and refined at its edge by bisection. With a stage model, no shorter
  // than two periods of its resonance: what a corner has at and above the resonance is what
  // neither the stage's model nor the servo knows well (a 10 Hz line with 0.05 ms corners tracks
  // at 5 nm, with 1.2 ms at 1 nm, bench/tracking_table), for 2.3 % of a 10 Hz line.
  const double floor_s = resonance_corner_s(planner_.stage());
  const double longest = kMaxCornerShare / spec.frequency_hz;
  auto fits = [&](double tau) {
    TrajectorySpec t = spec;
    t.corner_s = tau;
    return feasible(dry_run_periodic(t));
  };
  const double target = std::min(floor_s, longest);
  if (fits(target)) {
    if (target > 0.0)
      note = "corners rounded over " + si(target * 1e3, "ms") + " (two periods of the stage's resonance)";
    return target;
  }
  // Grid points a factor sqrt(2) apart from T/8 down to T/8 / 2^10, nearest the target first.
  constexpr int kGrid = 21;
  double grid[kGrid];
  for (int i = 0; i < kGrid; ++i) grid[i] = longest * std::pow(2.0, -0.5 * i);
  int best = -1;
  double best_distance = kInf;
  for (int i = 0; i < kGrid; ++i) {
    const double distance = std::abs(std::log(grid[i] / std::max(target, grid[kGrid - 1])));
    if (distance < best_distance && fits(grid[i])) {
      best = i;
      best_distance = distance;
    }
  }
  if (best < 0) return longest;  // nothing fits: the caller refuses (or shapes) it at T/8
  // Bisect towards the target between the feasible point and its infeasible neighbour.
  double ok = grid[best];
  double bad = grid[best] < target ? (best > 0 ? grid[best - 1] : ok) : (best + 1 < kGrid ? grid[best + 1] : 0.0);
  if (bad != ok) {
    for (int i = 0; i < 10; ++i) {
      const double mid = 0.5 * (ok + bad);
      (fits(mid) ? ok : bad) = mid;
    }
  }
  note = "corners rounded over " + si(ok * 1e3, "ms") + " (the shortest the actuator's limits allow)";
  return ok;
}

double ReferenceAdmission::feasible_amplitude(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const {
  // The feedforward's rate and excursion grow about in proportion to the amplitude: scale by the
  // ratio, then check by a dry run and shrink until it passes.
  TrajectorySpec t = spec;
  PlanExtent now = e;
  for (int i = 0; i < 8; ++i) {
    double ratio = 1.0;
    const double allowed = config().tracking_slew_V_per_s();
    if (now.rate_max_V_per_s > allowed) ratio = std::min(ratio, allowed / now.rate_max_V_per_s);
    if (now.u_max_V > config().u_max_V && now.u_max_V > 0.0) ratio = std::min(ratio, config().u_max_V / now.u_max_V);
    if (now.u_min_V < config().u_min_V && now.u_min_V < 0.0) ratio = std::min(ratio, config().u_min_V / now.u_min_V);
    t.amplitude_m *= 0.99 * ratio;
    now = dry_run_periodic(t);
    if (feasible(now) && feasible(dry_run(t, start_s))) return t.amplitude_m;
  }
  return 0.0;
}

std::string ReferenceAdmission::infeasibility(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const {
  std::string why = limits_left(e);
  const double slew_allowed = config().tracking_slew_V_per_s();
  const bool slew = e.rate_max_V_per_s > slew_allowed;
  if (periodic(spec)) {
    const double a = feasible_amplitude(spec, start_s, e);
    if (std::abs(a) > 0.0) {
      why += "; at " + si(spec.frequency_hz, "Hz") + " the largest feasible amplitude is " + si(a * 1e6, "um");
    }
    if (slew && e.u_min_V >= config().u_min_V && e.u_max_V <= config().u_max_V) {
      why += "; at " + si(spec.amplitude_m * 1e6, "um") + " the highest feasible frequency is about " +
             si(spec.frequency_hz * slew_allowed / e.rate_max_V_per_s, "Hz");
    }
    why += " (or ask for it shaped: hystloop-ctl trajectory --shape-to-feasible)";
  }
  return why;
}

std::string ReferenceAdmission::limits_left(const PlanExtent& e) const {
  std::string why;
  if (e.rate_max_V_per_s > config().tracking_slew_V_per_s()) {
    why = "its feedforward needs " + si(e.rate_max_V_per_s, "V/s") + ", above " +
          si(100.0 * config().tracking_slew_fraction(), "%") + " of the actuator's slew limit " +
          si(config().slew_V_per_s, "V/s") +
          " (actuator.slew_V_per_s; the rest is the servo's headroom, compensator.servo_slew_reserve)";
  }
  if (e.u_min_V < config().u_min_V || e.u_max_V > config().u_max_V) {
    if (!why.empty()) why += ", and ";
    why += "its feedforward needs u from " + si(e.u_min_V, "V") + " to " + si(e.u_max_V, "V") +
           ", outside the actuator's range " + si(config().u_min_V, "V") + " to " + si(config().u_max_V, "V") +
           " (actuator.u_min_V/u_max_V)";
  }
  return why;
}

void ReferenceAdmission::check_line_under(const ModelParamSet& candidate, bool switch_model) const {
  const FeedforwardPlanner& p = planner_;
  if (p.next_tick() < 0 || p.in_experiment()) return;
  const ScanShare* scan = p.scanning() ? p.scan() : nullptr;
  if (scan == nullptr && !periodic(p.trajectory())) return;
  const FeedforwardMode mode = p.mode();
  const bool in_use = (switch_model && mode != FeedforwardMode::kOff) || mode_of(candidate.kind) == mode ||
                      (!switch_model && mode == FeedforwardMode::kMem);
  if (!in_use) return;       // a set for a model not in use changes nothing the line needs
  FeedforwardPlanner c = p;  // off the per-sample path: the line planned as if the set were in
  c.swap_in_now(candidate, switch_model);
  const CompensatorConfig& cfg = config();
  if (scan != nullptr) {  // what is left of the path, planned under the set (the slew only, as below)
    c.begin_extent();
    const std::int64_t end = std::min(p.next_tick() + kDryRunMaxTicks,
                                      static_cast<std::int64_t>(std::ceil((scan->end_s() + 0.01) / cfg.dt_s)));
    for (std::int64_t k = p.next_tick(); k <= end; ++k) c.plan_tick(k, nullptr);
    PlanExtent e = c.extent();
    e.u_min_V = std::max(e.u_min_V, cfg.u_min_V);
    e.u_max_V = std::min(e.u_max_V, cfg.u_max_V);
    if (!feasible(e)) {
      throw ParameterError("params", "under this set the scan in force (axis " + std::string(axis_name(scan->axis())) +
                                         ") would leave the actuator's limits: " + limits_left(e) +
                                         "; the set in use stays");
    }
    return;
  }
  // The slew only: a set asking a volt beyond the range at the line's extremes is clamped there
  // by the plan, a loss of nanometres at two points, where refusing it could keep a set that a
  // wrong start left far off (the demo's repair); beyond the slew the whole line is held back.
  PlanExtent e = ReferenceAdmission(c).dry_run_periodic(p.trajectory());
  e.u_min_V = std::max(e.u_min_V, cfg.u_min_V);
  e.u_max_V = std::min(e.u_max_V, cfg.u_max_V);
  const std::string line = "the line in force (" + si(p.trajectory().amplitude_m * 1e6, "um") + " at " +
                           si(p.trajectory().frequency_hz, "Hz") + ")";
  if (!feasible(e)) {
    throw ParameterError("params", "under this set " + line + " would leave the actuator's limits: " + limits_left(e) +
                                       "; the set in use stays");
  }
}

}  // namespace hystloop
