#include "loop/compensator.hpp"

#include <array>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// A triangle's corners are rounded over at most this share of the period each (the rest of the
// line is straight: what a raster scan uses).
constexpr double kMaxCornerShare = 0.125;
// Learning needs room beside a line: a line whose feedforward needs more of the slew limit than
// this is tracked without (reached only where compensator.servo_slew_reserve is set below 2 %).
constexpr double kLearningSlewShare = 0.97;
// A dry run covers the approach and this many periods: both corners and the branch after each.
constexpr double kDryRunPeriods = 1.25;
constexpr std::int64_t kDryRunMaxTicks = 200'000;

std::string si(double value, const char* unit) { return number_text(value, 3) + " " + unit; }
}  // namespace

double resonance_corner_s(const StageModel& stage) noexcept {
  return stage.has_dynamics() ? 2.0 * 2.0 * std::numbers::pi / stage.second_order.natural_frequency() : 0.0;
}

// Each online model's mode number is its registry entry's (models/model_set.hpp).
FeedforwardMode mode_of(ModelKind kind) noexcept {
  FeedforwardMode mode = FeedforwardMode::kOff;
  OnlineModels::visit(kind, [&]<class D>() { mode = static_cast<FeedforwardMode>(D::mode); });
  return mode;
}

std::optional<ModelKind> model_kind_of(FeedforwardMode mode) noexcept {
  std::optional<ModelKind> kind;
  OnlineModels::for_each([&]<class D>() {
    if (static_cast<FeedforwardMode>(D::mode) == mode) kind = D::kind;
  });
  return kind;
}

// The models' names are ModelKind's (models/model_set.cpp): one table for the compensator's
// config, HX_CONTROL's SET_MODE (hystloop-ctl mode) and the re-identifier's model choice.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field) {
  if (name == "off") return FeedforwardMode::kOff;
  if (const auto kind = parse_model_kind(name)) return mode_of(*kind);
  throw ParameterError(field, "unknown mode '" + name + "' (expected " + selectable_mode_choices() + ")");
}

std::string selectable_mode_choices() {
  std::vector<std::pair<std::int8_t, std::string_view>> modes{{static_cast<std::int8_t>(FeedforwardMode::kOff), "off"}};
  OnlineModels::for_each([&]<class D>() { modes.emplace_back(D::mode, D::name); });
  std::sort(modes.begin(), modes.end());
  std::vector<std::string_view> names;
  names.reserve(modes.size());
  for (const auto& [number, name] : modes) names.push_back(name);
  return choice_list(names);
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
  OnlineModels::for_each([&]<class D>() { (models.*D::in_set).validate(); });
  require_in_range("compensator.dt_s", dt_s, 1e-6, 1.0);
  require_finite("compensator.u_min_V", u_min_V);
  require_finite("compensator.u_max_V", u_max_V);
  if (!(u_min_V < u_max_V)) throw ParameterError("compensator.u_max_V", "must exceed u_min_V");
  require_positive("compensator.slew_V_per_s", slew_V_per_s);
  require_in_range("compensator.reanchor_ticks", static_cast<double>(reanchor_ticks), 1.0, 1000.0);
  require_in_range("compensator.reanchor_ramp_ticks", static_cast<double>(reanchor_ramp_ticks), 1.0, 100000.0);
  require_in_range("compensator.slew_fraction", slew_fraction, 1e-12, 1.0);
  require_positive("compensator.reanchor_u_rate_V_per_s", reanchor_u_rate_V_per_s);
  stage.validate(dt_s);
  learning.validate(dt_s);
  require_in_range("compensator.plan_slew_fraction", plan_slew_fraction, 0.05, 1.0);
  require_in_range("compensator.servo_slew_reserve", servo_slew_reserve, 0.0, plan_slew_fraction - 0.05);
  if (horizon_ticks < 1 || horizon_ticks > kMaxHorizonTicks) {
    throw ParameterError("compensator.horizon_s", "must be 1 to " + std::to_string(kMaxHorizonTicks) + " ticks (got " +
                                                      std::to_string(horizon_ticks) + ")");
  }
}

Compensator::Compensator(const CompensatorConfig& config)
    : config_((config.validate(), config)),
      mode_(config.mode),
      inverses_(config.models),
      anchor_offset_(config.reanchor_ticks, config.reanchor_ramp_ticks,
                     config.slew_fraction * config.slew_V_per_s * config.dt_s,
                     config.reanchor_u_rate_V_per_s * config.dt_s),
      // Samples arrive up to the horizon after their tick was planned, plus a block or two.
      learner_(config.learning, config.dt_s, config.horizon_ticks + 2000) {
  reversals_.reset(0.0);
  set_stage(config.stage);
  counters_.stage_swaps = 0;
}

void Compensator::set_stage(const StageModel& stage) noexcept {
  stage_model_ = stage;
  if (stage.has_dynamics()) {
    stage_inverse_.emplace(stage.second_order, config_.dt_s);  // validated by the caller
    servo_share_stage_.emplace(stage.second_order);
  } else {
    stage_inverse_.reset();
    servo_share_stage_.reset();
  }
  servo_share_seq_ = -1;
  stage_fresh_ = true;
  ++counters_.stage_swaps;
}

void Compensator::set_learning(bool on) noexcept { learner_.set_enabled(on); }

void Compensator::reset_learning() noexcept { learner_.reset(); }

const TrajectorySpec& Compensator::periodic_reference() const noexcept {
  if (scan_) {
    if (const TrajectorySpec* fast = scan_->share.periodic_part()) return *fast;
  }
  return trajectory_;
}

Compensator::ReferencePoint Compensator::reference_point(const TrajectorySpec& trajectory,
                                                         const std::optional<ScanInForce>& scan, double t_s) noexcept {
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

void Compensator::restart_learning(std::int64_t k) noexcept {
  // A scan's hold (the trajectory under it) is not periodic: without a periodic part, no learning.
  const TrajectorySpec& reference = periodic_reference();
  const auto period = period_ticks(reference, config_.dt_s);
  if (!period || !learning_room_) {
    learner_.stop();
    return;
  }
  // Phase 0 a quarter period after the shape is entered (the approach before it is not
  // periodic): a new table is adopted at a period boundary, and its change is a small step of the
  // reference there, harmless where the reference moves fastest but, at a reversal, a tiny extra
  // reversal of the voltage: a minor loop the stage does not close (Coleman-Hodgdon's next branch
  // moves by ~2 alpha (f - y) du), i.e. a random offset until the next period's learning.
  const double phase0_s = reference.start_s + first_extreme_s(reference) + 0.25 / reference.frequency_hz;
  const auto k0 = static_cast<std::int64_t>(std::ceil(phase0_s / config_.dt_s - 1e-9));
  learner_.restart(std::max(k, k0), *period);
}

bool Compensator::set_trajectory(TrajectorySpec spec, double start_s) { return take_trajectory(spec, start_s).started; }

TrajectoryVerdict Compensator::take_trajectory(TrajectorySpec spec, double start_s) {
  spec.validate();
  if (!std::isnan(start_s)) require_finite("trajectory.start_s", start_s);
  TrajectoryVerdict v;
  if (spec.shape == TrajectoryShape::kTriangle && spec.corner_s == 0.0) spec.corner_s = choose_corner(spec, v.note);
  PlanExtent e = dry_run(spec, start_s);
  if (!feasible(e)) {
    if (!spec.shape_if_infeasible || !periodic(spec)) {
      ++counters_.trajectories_refused;
      throw ParameterError("trajectory", infeasibility(spec, start_s, e));
    }
    const double a = feasible_amplitude(spec, start_s, e);
    if (!(std::abs(a) > 0.0)) {
      ++counters_.trajectories_refused;
      throw ParameterError("trajectory", infeasibility(spec, start_s, e) + "; no amplitude is feasible");
    }
    if (!v.note.empty()) v.note += "; ";
    v.note += "amplitude " + si(spec.amplitude_m * 1e6, "um") + " scaled to " + si(a * 1e6, "um") +
              " to stay inside the actuator's limits";
    spec.amplitude_m = a;
    e = dry_run(spec, start_s);
    v.shaped = true;
    ++counters_.trajectories_shaped;
  }
  v.extent = e;
  // Learning needs room beside the line: its corrections and the servo share what the line leaves
  // of the slew limit. A line using more than kLearningSlewShare of it is tracked without
  // (measured: at 98 % a 200 Hz line clamps on 2 % of its ticks with learning and gains nothing).
  learning_room_ = e.rate_max_V_per_s <= kLearningSlewShare * config_.slew_V_per_s;
  if (!learning_room_ && periodic(spec) && learner_.enabled()) {
    if (!v.note.empty()) v.note += "; ";
    v.note += "learning off for it: the line needs " + si(100.0 * e.rate_max_V_per_s / config_.slew_V_per_s, "%") +
              " of the slew limit, no room for corrections";
  }
  v.started = !(!std::isnan(start_s) && next_tick_ >= 0 && start_s - spec.blend_s < loop_time(next_tick_));
  apply_trajectory(spec, start_s);
  v.spec = trajectory_;
  return v;
}

void Compensator::apply_trajectory(const TrajectorySpec& given, double start_s, const ScanShare* scan) noexcept {
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

PlanExtent Compensator::dry_run(const TrajectorySpec& spec, double start_s) const {
  return dry_run(spec, start_s, nullptr);
}

PlanExtent Compensator::dry_run(const TrajectorySpec& spec, double start_s, const ScanShare* scan) const {
  Compensator c = *this;  // off the per-sample path: a copy plans what this one would
  c.learner_.stop();
  c.experiments_.stop(loop_time(std::max<std::int64_t>(next_tick_, 0)));
  std::int64_t k = std::max<std::int64_t>(next_tick_, 0);
  if (c.awaiting_anchor_ || c.in_experiment_) {  // the stage is about where the plan left it
    c.awaiting_anchor_ = false;
    c.in_experiment_ = false;
    c.restart_reference(c.loop_time(k), c.last_ref_);
  }
  c.apply_trajectory(spec, start_s, scan);
  c.extent_ = PlanExtent{kInf, -kInf, 0.0, 0};
  c.last_u_wanted_ = kNaN;
  // Through the approach and what shows what the reference needs: a scan's whole path, a periodic
  // shape's first periods, a point list's points.
  double until_s = 0.0;
  if (scan != nullptr) {
    until_s = scan->end_s() + 0.01;
  } else {
    TrajectorySpec from_here = spec;
    from_here.hold_m = c.last_ref_;  // where the approach starts decides where the shape is entered
    const double t0 =
        (c.trajectory_starts_now_ ? c.loop_time(k) + spec.blend_s : c.trajectory_.start_s) + first_extreme_s(from_here);
    double span = 0.01;
    if (periodic(spec)) span = kDryRunPeriods / spec.frequency_hz;
    if (spec.shape == TrajectoryShape::kPoints && spec.n_points > 0) span = spec.points_t_s[spec.n_points - 1] + 0.01;
    until_s = t0 + span;
  }
  const std::int64_t end = std::min(k + kDryRunMaxTicks, static_cast<std::int64_t>(std::ceil(until_s / config_.dt_s)));
  for (; k <= end; ++k) c.plan_tick(k);
  return c.extent_;
}

TrajectoryVerdict Compensator::take_scan(const ScanShare& share, double blend_s) {
  const PlanExtent e = check_scan(share, blend_s);
  return apply_scan(share, blend_s, e);
}

PlanExtent Compensator::check_scan(const ScanShare& share, double blend_s) {
  require_in_range("scan.blend_s", blend_s, 0.0, 60.0);
  TrajectorySpec hold;
  hold.shape = TrajectoryShape::kHold;
  hold.offset_m = share.point(share.start_s()).own_m;
  hold.blend_s = blend_s;
  hold.validate();
  const double next_s = loop_time(std::max<std::int64_t>(next_tick_, 0));
  if (in_experiment_ || awaiting_anchor_ || experiments_.running() || experiments_.queued() > 0) {
    ++counters_.trajectories_refused;
    throw ParameterError("scan",
                         "an identification experiment is running or queued: its end restarts the "
                         "reference, which would leave this axis behind the path the others follow");
  }
  if (share.end_s() - next_s > static_cast<double>(kDryRunMaxTicks) * config_.dt_s) {
    ++counters_.trajectories_refused;
    throw ParameterError("scan", "ends " + si(share.end_s() - next_s, "s") +
                                     " of loop time from now; a path is checked whole before it is taken, at "
                                     "most " +
                                     si(static_cast<double>(kDryRunMaxTicks) * config_.dt_s, "s") + " ahead");
  }
  if (share.start_s() - blend_s < next_s) {
    ++counters_.trajectories_refused;
    throw ParameterError("scan.start_s", "must leave the approach (" + si(blend_s, "s") + ") before it: starts at " +
                                             si(share.start_s(), "s") + ", the next tick not yet planned is at " +
                                             si(next_s, "s") + " (loop time)");
  }
  const PlanExtent e = dry_run(hold, share.start_s(), &share);  // the approach and the whole path
  if (!feasible(e)) {
    ++counters_.trajectories_refused;
    throw ParameterError("scan", "axis " + std::string(axis_name(share.axis())) + ": " + limits_left(e));
  }
  return e;
}

TrajectoryVerdict Compensator::apply_scan(const ScanShare& share, double blend_s, const PlanExtent& checked) {
  TrajectorySpec hold;
  hold.shape = TrajectoryShape::kHold;
  hold.offset_m = share.point(share.start_s()).own_m;
  hold.blend_s = blend_s;
  TrajectoryVerdict v;
  v.extent = checked;
  learning_room_ = checked.rate_max_V_per_s <= kLearningSlewShare * config_.slew_V_per_s;
  apply_trajectory(hold, share.start_s(), &share);
  v.spec = trajectory_;
  return v;
}

void take_scan_on_every_axis(std::span<Compensator* const> laws, std::span<const ScanShare> shares, double blend_s) {
  if (laws.size() != shares.size()) throw ParameterError("scan", "one share per axis");
  std::array<PlanExtent, kMaxAxes> checked{};
  if (laws.size() > checked.size()) throw ParameterError("scan", "at most " + std::to_string(kMaxAxes) + " axes");
  for (std::size_t i = 0; i < laws.size(); ++i) checked[i] = laws[i]->check_scan(shares[i], blend_s);
  for (std::size_t i = 0; i < laws.size(); ++i) laws[i]->apply_scan(shares[i], blend_s, checked[i]);
}

PlanExtent Compensator::dry_run_periodic(const TrajectorySpec& spec) const {
  // As if the plan were already at the point where the shape is entered, at rest: no approach to
  // plan (a search over corners or amplitudes would otherwise plan the same approach each time).
  Compensator c = *this;
  c.learner_.stop();
  c.experiments_.stop(loop_time(std::max<std::int64_t>(next_tick_, 0)));
  c.awaiting_anchor_ = false;
  c.in_experiment_ = false;
  std::int64_t k = std::max<std::int64_t>(next_tick_, 0);
  TrajectorySpec t = spec;
  t.hold_m = c.last_ref_;
  t.start_s = 0.0;
  const double enter = first_extreme_s(t);
  c.restart_reference(c.loop_time(k), evaluate_shape(t, enter));
  t.blend_s = 0.0;
  t.start_s = c.loop_time(k) - enter;  // the shape's tau at tick k is `enter`
  t.hold_m = c.last_ref_;
  c.trajectory_ = t;
  c.trajectory_starts_now_ = false;
  c.trajectory_timed_ = true;
  // A period to settle (the jump to the entry and the step in acceleration there ring the stage's
  // inverse, which the real approach avoids), then what the periods need.
  const auto period = static_cast<std::int64_t>(std::ceil(1.0 / (spec.frequency_hz * config_.dt_s)));
  for (const std::int64_t settle_end = k + period; k < settle_end; ++k) c.plan_tick(k);
  c.extent_ = PlanExtent{kInf, -kInf, 0.0, 0};
  const std::int64_t end = k + static_cast<std::int64_t>(std::ceil(kDryRunPeriods * static_cast<double>(period)));
  for (; k <= end; ++k) c.plan_tick(k);
  return c.extent_;
}

bool Compensator::feasible(const PlanExtent& e) const noexcept {
  if (e.ticks == 0) return true;
  return e.rate_max_V_per_s <= config_.tracking_slew_V_per_s() && e.u_min_V >= config_.u_min_V &&
         e.u_max_V <= config_.u_max_V;
}

double Compensator::choose_corner(const TrajectorySpec& spec, std::string& note) const {
  // The shortest rounding the limits allow. A sharp corner asks the inverse for a voltage rate
  // that only the slope of the branch just after the reversal bounds (with the stage's inverse,
  // for an infinite one); a long one makes the straight line steeper (its slope is
  // 2A / (T/2 - tau (1 - 2/pi))). So the feasible corners are a band, found on a grid of dry runs
  // (without the approach) and refined at its edge by bisection. With a stage model, no shorter
  // than two periods of its resonance: what a corner has at and above the resonance is what
  // neither the stage's model nor the servo knows well (a 10 Hz line with 0.05 ms corners tracks
  // at 5 nm, with 1.2 ms at 1 nm, bench/tracking_table), for 2.3 % of a 10 Hz line.
  const double floor_s = resonance_corner_s(stage_model_);
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

double Compensator::feasible_amplitude(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const {
  // The feedforward's rate and excursion grow about in proportion to the amplitude: scale by the
  // ratio, then check by a dry run and shrink until it passes.
  TrajectorySpec t = spec;
  PlanExtent now = e;
  for (int i = 0; i < 8; ++i) {
    double ratio = 1.0;
    const double allowed = config_.tracking_slew_V_per_s();
    if (now.rate_max_V_per_s > allowed) ratio = std::min(ratio, allowed / now.rate_max_V_per_s);
    if (now.u_max_V > config_.u_max_V && now.u_max_V > 0.0) ratio = std::min(ratio, config_.u_max_V / now.u_max_V);
    if (now.u_min_V < config_.u_min_V && now.u_min_V < 0.0) ratio = std::min(ratio, config_.u_min_V / now.u_min_V);
    t.amplitude_m *= 0.99 * ratio;
    now = dry_run_periodic(t);
    if (feasible(now) && feasible(dry_run(t, start_s))) return t.amplitude_m;
  }
  return 0.0;
}

std::string Compensator::infeasibility(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const {
  std::string why = limits_left(e);
  const double slew_allowed = config_.tracking_slew_V_per_s();
  const bool slew = e.rate_max_V_per_s > slew_allowed;
  if (periodic(spec)) {
    const double a = feasible_amplitude(spec, start_s, e);
    if (std::abs(a) > 0.0) {
      why += "; at " + si(spec.frequency_hz, "Hz") + " the largest feasible amplitude is " + si(a * 1e6, "um");
    }
    if (slew && e.u_min_V >= config_.u_min_V && e.u_max_V <= config_.u_max_V) {
      why += "; at " + si(spec.amplitude_m * 1e6, "um") + " the highest feasible frequency is about " +
             si(spec.frequency_hz * slew_allowed / e.rate_max_V_per_s, "Hz");
    }
    why += " (or ask for it shaped: hystloop-ctl trajectory --shape-to-feasible)";
  }
  return why;
}

std::string Compensator::limits_left(const PlanExtent& e) const {
  std::string why;
  if (e.rate_max_V_per_s > config_.tracking_slew_V_per_s()) {
    why = "its feedforward needs " + si(e.rate_max_V_per_s, "V/s") + ", above " +
          si(100.0 * config_.tracking_slew_fraction(), "%") + " of the actuator's slew limit " +
          si(config_.slew_V_per_s, "V/s") +
          " (actuator.slew_V_per_s; the rest is the servo's headroom, compensator.servo_slew_reserve)";
  }
  if (e.u_min_V < config_.u_min_V || e.u_max_V > config_.u_max_V) {
    if (!why.empty()) why += ", and ";
    why += "its feedforward needs u from " + si(e.u_min_V, "V") + " to " + si(e.u_max_V, "V") +
           ", outside the actuator's range " + si(config_.u_min_V, "V") + " to " + si(config_.u_max_V, "V") +
           " (actuator.u_min_V/u_max_V)";
  }
  return why;
}

void Compensator::check_running_line(const ModelParamSet& candidate, bool switch_model) const {
  if (next_tick_ < 0 || in_experiment_ || awaiting_anchor_) return;
  const bool scanning = scan_ && !scan_->lines_over;
  if (!scanning && !periodic(trajectory_)) return;
  const bool in_use = (switch_model && mode_ != FeedforwardMode::kOff) || mode_of(candidate.kind) == mode_ ||
                      (!switch_model && mode_ == FeedforwardMode::kMem);
  if (!in_use) return;    // a set for a model not in use changes nothing the line needs
  Compensator c = *this;  // off the per-sample path: the line planned as if the set were in
  c.pending_ = Pending{candidate, switch_model};
  c.swap_params(next_tick_);
  if (scanning) {  // what is left of the path, planned under the set (the slew only, as below)
    c.learner_.stop();
    c.extent_ = PlanExtent{kInf, -kInf, 0.0, 0};
    c.last_u_wanted_ = kNaN;
    const std::int64_t end =
        std::min(next_tick_ + kDryRunMaxTicks,
                 static_cast<std::int64_t>(std::ceil((scan_->share.end_s() + 0.01) / config_.dt_s)));
    for (std::int64_t k = next_tick_; k <= end; ++k) c.plan_tick(k);
    PlanExtent e = c.extent_;
    e.u_min_V = std::max(e.u_min_V, config_.u_min_V);
    e.u_max_V = std::min(e.u_max_V, config_.u_max_V);
    if (!feasible(e)) {
      throw ParameterError("params",
                           "under this set the scan in force (axis " + std::string(axis_name(scan_->share.axis())) +
                               ") would leave the actuator's limits: " + limits_left(e) + "; the set in use stays");
    }
    return;
  }
  // The slew only: a set asking a volt beyond the range at the line's extremes is clamped there
  // by the plan, a loss of nanometres at two points, where refusing it could keep a set that a
  // wrong start left far off (the demo's repair); beyond the slew the whole line is held back.
  PlanExtent e = c.dry_run_periodic(trajectory_);
  e.u_min_V = std::max(e.u_min_V, config_.u_min_V);
  e.u_max_V = std::min(e.u_max_V, config_.u_max_V);
  const std::string line = "the line in force (" + si(trajectory_.amplitude_m * 1e6, "um") + " at " +
                           si(trajectory_.frequency_hz, "Hz") + ")";
  if (!feasible(e)) {
    throw ParameterError("params", "under this set " + line + " would leave the actuator's limits: " + limits_left(e) +
                                       "; the set in use stays");
  }
}

void Compensator::offer_mem_params(const MemParams& params, std::int32_t version) {
  ModelParamSet set;
  set.mem = params;
  offer(set, false, version);
}

void Compensator::offer_model(const ModelParamSet& params, std::int32_t version) { offer(params, true, version); }

void Compensator::offer(const ModelParamSet& set, bool switch_model, std::int32_t version) {
  try {
    if (switch_model) {
      set.validate(config_.dt_s);
    } else {
      set.mem.validate();  // MEM's parameters only: the rest of the set is not offered
    }
    check_running_line(set, switch_model);
  } catch (const ParameterError&) {
    ++counters_.params_rejected;
    throw;
  }
  pending_ = Pending{set, switch_model};
  pending_version_ = version;
  ++counters_.params_accepted;
}

ModelParamSet Compensator::model_params() const noexcept {
  ModelParamSet set;
  inverses_.get_params(set);
  set.kind = model_kind_of(mode_).value_or(ModelKind::mem);
  return set;
}

double Compensator::nominal_slope() const noexcept {
  return inverses_.nominal_slope(model_kind_of(mode_).value_or(ModelKind::linear));
}

double Compensator::restart_at_reversal(FeedforwardMode mode, double u_rev) noexcept {
  const double w = last_w_ - shift_m_;
  const auto kind = model_kind_of(mode);
  return kind ? inverses_.restart_at_reversal(*kind, u_prev_rev_, u_rev, w) : w;
}

bool Compensator::params_held_by_learning() const noexcept {
  if (!pending_) return false;
  const LearnerFigures& f = learner_.figures();
  const std::int64_t after = config_.learning.hold_params_after;
  if (after <= 0 || !f.active || f.tables_this_line < static_cast<std::uint64_t>(after)) return false;
  // A table near its bound is no converged line: a model far off, which the new set may repair.
  if (!(f.correction_rms_m < 0.5 * config_.learning.max_correction_m)) return false;
  // A set for a model the line does not use changes nothing it learned: it goes in as always.
  return pending_switches_model() || mode_of(pending_->params.kind) == mode_;
}

bool Compensator::pending_switches_model() const noexcept {
  const FeedforwardMode to = mode_of(pending_->params.kind);
  return pending_->switch_model && mode_ != FeedforwardMode::kOff && to != mode_;
}

void Compensator::swap_params(std::int64_t k) noexcept {
  const ModelParamSet& p = pending_->params;
  const FeedforwardMode to = mode_of(p.kind);
  const bool switching = pending_switches_model();
  const bool in_use = switching || to == mode_;
  const double u_shift = anchor_offset_.u_offset(k);
  const double u_rev = last_u_ - u_shift;  // this reversal, in the model's coordinates
  inverses_.set_params(p);
  if (p.stage) set_stage(*p.stage);  // at a reversal the stage is nearly at rest: restart it there
  params_version_ = pending_version_;
  pending_.reset();
  ++counters_.params_swapped;
  if (!in_use) return;
  if (switching) {
    mode_ = to;
    ++counters_.model_switches;
  }
  // A line learning under the old set that has no table yet: what it has observed is the old
  // set's error, which its first table would carry over to the new one. It learns from here.
  if (learner_.figures().active && learner_.figures().tables_this_line == 0) learner_.reset();
  // At a reversal the inverse starts a new branch from its last point: new parameters change
  // the slope of what follows, never the voltage already reached. MEM remembers nothing else;
  // the others restart at this reversal, and the offset takes up where their output is there.
  if (switching || mode_ != FeedforwardMode::kMem) {
    anchor_offset_.reset(last_w_ - restart_at_reversal(mode_, u_rev), u_shift);
  }
  if (mode_ == FeedforwardMode::kLinear) {
    // A line has no branch to anchor: its fitted offset puts it through the middle of the loop,
    // where anchoring it at a reversal would put it at the loop's edge. Ramp back to that.
    anchor_offset_.ramp_to(0.0, u_shift, k, inverses_.linear_params().gain);
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
    if (counters_.planned > 0) anchor_ = StagePoint{last_u_, last_w_, kNaN};
  }
}

void Compensator::start_experiment(const ExperimentSpec& spec) {
  spec.validate();
  // An excitation is a voltage: it must fit the actuator as it is, not be clamped by the bridge.
  if (spec.offset_V - spec.amplitude_V < config_.u_min_V || spec.offset_V + spec.amplitude_V > config_.u_max_V) {
    throw ParameterError("experiment", "offset " + si(spec.offset_V, "V") + " +- amplitude " +
                                           si(spec.amplitude_V, "V") + " leaves the actuator's range " +
                                           si(config_.u_min_V, "V") + " to " + si(config_.u_max_V, "V") +
                                           " (actuator.u_min_V/u_max_V)");
  }
  const double rate = 2.0 * std::numbers::pi * spec.frequency_hz * spec.amplitude_V;
  if (rate > config_.plan_slew_fraction * config_.slew_V_per_s) {
    throw ParameterError(
        "experiment",
        "a sine of " + si(spec.amplitude_V, "V") + " at " + si(spec.frequency_hz, "Hz") + " needs " + si(rate, "V/s") +
            ", above " + si(100.0 * config_.plan_slew_fraction, "%") + " of the slew limit " +
            si(config_.slew_V_per_s, "V/s") + " (actuator.slew_V_per_s): at most " +
            si(config_.plan_slew_fraction * config_.slew_V_per_s / (2.0 * std::numbers::pi * spec.amplitude_V), "Hz") +
            " at this amplitude");
  }
  experiments_.add(spec);
}

void Compensator::stop_experiment() noexcept { experiments_.stop(loop_time(std::max<std::int64_t>(next_tick_, 0))); }

void Compensator::reset_inverse(double y0) noexcept {
  if (const auto kind = model_kind_of(mode_)) inverses_.start(*kind, y0, anchor_);
}

double Compensator::feedforward(double y_ref) noexcept {
  const auto kind = model_kind_of(mode_);
  return kind ? inverses_.inverse(*kind, y_ref) : 0.0;
}

void Compensator::observe(const CompensatorInput& sample) noexcept {
  switch (ticks_.observe(sample.seq, 1)) {
    case SequenceGapDetector::Outcome::kFirst:
    case SequenceGapDetector::Outcome::kInOrder:
    case SequenceGapDetector::Outcome::kGap: break;
    default: ++counters_.out_of_order; return;  // late, repeated or outside the contract
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
  if (anchor_offset_.observe(sample.seq, sample.y_m, sample.u_V, next_tick_, nominal_slope())) ++counters_.reanchors;
  learner_.observe(sample.seq, sample.y_m - servo_share_m(sample));
}

double Compensator::servo_share_m(const CompensatorInput& sample) noexcept {
  // The learning corrects the feedforward, so it must see the feedforward's own error. The servo
  // on y_ref - y works against every correction (what reaches the position is the correction
  // times the loop's sensitivity S, 0.16 at 50 Hz with the default gains), which would slow the
  // learning to a crawl where S is small and leave the update's premise, a plant from correction
  // to position near 1, untrue. The position the servo's voltage bought, the stage (linearised at
  // the linear model's gain) driven by u_V - u_ff_V, is taken out of the measurement: what is left
  // is y_ff, the position the feedforward alone would have made, and r - y_ff is what the
  // learning removes. Noise is untouched (it enters y, not u_ff), so the noise bound holds as is.
  const double du = sample.u_V - sample.u_ff_V;
  const bool consecutive = servo_share_seq_ >= 0 && sample.seq == servo_share_seq_ + 1;
  servo_share_seq_ = sample.seq;
  if (!std::isfinite(du)) return 0.0;
  const double w = inverses_.linear_params().gain * du;
  if (!servo_share_stage_) return w;
  if (!consecutive) servo_share_stage_->reset(w);
  return servo_share_stage_->step(w, config_.dt_s);
}

Compensator Compensator::restarted(CompensatorConfig config, std::string& refusal) const {
  config.models.mem = mem_params();
  config.mode = mode();
  TrajectorySpec reference = trajectory();
  reference.hold_m = 0.0;
  Compensator next(config);
  // The parameter sets given here: the one in use with its version, and one waiting for a reversal.
  next.inverses_.take_params_from(inverses_);
  next.params_version_ = params_version_;
  next.set_stage(stage_model_);
  next.counters_.stage_swaps = 0;  // the same stage: no swap
  next.learner_.set_enabled(learner_.enabled());
  next.pending_ = pending_;
  next.pending_version_ = pending_version_;
  refusal.clear();
  try {
    next.set_trajectory(reference, kNaN);
  } catch (const ParameterError& e) {
    // Taken before, infeasible now (the sets in use changed since): hold where the new law starts
    // rather than clamp; the operator sends it again, or a feasible one.
    next.set_trajectory(TrajectorySpec{}, kNaN);
    refusal = e.what();
  }
  return next;
}

void Compensator::restart_reference(double t_s, double from_m) noexcept {
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
      learner_.stop();  // an excitation is no period of the reference
    } else {
      experiment_u_.update(e.voltage_V);
    }
    // From where the plan is (the previous experiment's offset, or the tracking voltage) at the
    // slew limit's admitted share: the bridge never has to clamp an excitation.
    const double max_step = config_.plan_slew_fraction * config_.slew_V_per_s * config_.dt_s;
    double u = e.voltage_V;
    if (std::abs(u - last_u_) > max_step) {
      u = last_u_ + std::copysign(max_step, u - last_u_);
      ++counters_.experiment_ramped;
    }
    last_u_ = u;
    last_u_wanted_ = kNaN;
    return {k, u, kNaN, params_version_, kExperimentMode};
  }
  if (e.ended) {
    awaiting_anchor_ = true;
    anchor_tick_ = k;
    in_experiment_ = false;
    experiment_branch_u_ = experiment_u_.turning_point();
  }
  if (awaiting_anchor_) {
    last_u_wanted_ = kNaN;
    return {k, last_u_, kNaN, params_version_, static_cast<std::int8_t>(mode_)};
  }
  return tracking_tick(k);
}

CommandTick Compensator::tracking_tick(std::int64_t k) noexcept {
  const double t = loop_time(k);
  if (trajectory_starts_now_) {
    trajectory_.start_s = t + trajectory_.blend_s;
    trajectory_.hold_m = last_ref_;
    trajectory_starts_now_ = false;
  }
  if (learner_restart_) {
    restart_learning(k);
    learner_restart_ = false;
  }
  // The lines are over: the raster holds its end, no period left to learn.
  if (scan_ && !scan_->lines_over && t >= scan_->share.end_s()) {
    scan_->lines_over = true;
    if (scan_->share.periodic_part()) learner_.stop();
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
  // The sensor's reference (the servo's, the learning's, the anchor's) and the one the inverses aim
  // the axis's own displacement at: equal but during a decoupled scan.
  const double y_ref = ref.sensor_m;
  const double y_aim = ref.aim_m;
  if (reversals_.update(y_aim) == ReversalDetector::Event::kReversal) {
    ++counters_.reversals;
    if (pending_ && !params_held_by_learning()) swap_params(k);
    u_prev_rev_ = last_u_ - anchor_offset_.u_offset(k);
  }
  if (inverse_fresh_) {
    reset_inverse(y_aim);
    inverse_fresh_ = false;
    anchor_.reset();
    if (anchor_offset_.measuring()) ++counters_.reanchors_skipped;
    anchor_offset_.reset(0.0);
    u_prev_rev_ = last_u_;
  }
  // The reference the inverse aims at: with what the learning has found this point of the period
  // needs, and, for hysteresis then stage, through the stage's inverse first.
  const double correction = learner_.correction(k, y_ref);
  const double r = y_aim + correction;
  const bool stage_first = stage_inverse_ && stage_model_.order == BanningOrder::kHysteresisThenStage;
  if (stage_first && stage_fresh_) {
    stage_inverse_->reset(r);
    stage_fresh_ = false;
  }
  const double w_ref = stage_first ? stage_inverse_->step(r) : r;
  shift_m_ = anchor_offset_.y_offset(k);
  const double shift_V = anchor_offset_.u_offset(k);
  const double y_model = w_ref - shift_m_;
  double u = feedforward(y_model) + shift_V;
  if (stage_inverse_ && !stage_first) {  // stage then hysteresis: the stage's input from its output
    if (stage_fresh_) {
      stage_inverse_->reset(u);
      stage_fresh_ = false;
    }
    u = stage_inverse_->step(u);
  }
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
      learner_.hold(k);
    }
  };
  if (u < config_.u_min_V || u > config_.u_max_V) {
    limited(counters_.u_clamped);
    u = std::clamp(u, config_.u_min_V, config_.u_max_V);
  }
  // The plan keeps within the share of the slew limit a trajectory was admitted at (the rest is
  // the servo's, beside the sensor); what learning or a swap would ask beyond it is held back here
  // and counted, not clamped by the bridge behind the servo's back.
  const double max_step = config_.tracking_slew_V_per_s() * config_.dt_s;
  if (std::abs(u - last_u_) > max_step) {
    limited(counters_.u_slew_clamped);
    u = last_u_ + std::copysign(max_step, u - last_u_);
  }
  // The anchor compares the measured position with the reference the model was asked for (not
  // the learned correction: what the learning adds is meant to make y follow y_ref).
  anchor_offset_.planned(k, y_ref - shift_m_, u - shift_V);
  last_ref_ = y_ref;
  last_w_ = w_ref;
  last_u_ = u;
  return {k, u, y_ref, params_version_, static_cast<std::int8_t>(mode_)};
}

}  // namespace hystloop
