#pragma once
// The compensator's control law without I/O or a clock. It runs ahead of the bridge: after
// each sensor tick k it has planned the commands for every tick through k + horizon_ticks,
//
//   u_ff(j) = H^-1( y_ref(t_j) ),   y_ref(t_j) = the trajectory at t_j = j * dt,
//
// one inverse-model step per planned tick, with H^-1 the inverse of the selected hysteresis
// model. The bridge adds its servo on y_ref - y beside the sensor. Loop time is tick * dt, so
// the plan is a deterministic function of the messages given, in order: a recorded log
// replays to the same commands (tools/replay-check relies on it).
//
// With a stage model (config.stage), the reference first goes through the stage's exact inverse
// (models/stage_inverse.hpp) and then through the hysteresis inverse (the other way round for
// the stage-then-hysteresis order): the inverse of the whole series model. For a periodic
// reference a PeriodicLearner adds a correction per tick of the period, learned from the errors
// of earlier periods. A trajectory is checked before it is taken: a dry run of this plan over
// its approach and its first periods must stay inside the actuator's range and
// tracking_slew_fraction() of its slew limit, or it is refused with the limit named and the
// largest feasible amplitude and frequency (or shaped to feasibility when asked). A triangle's
// corners are rounded; with corner_s 0 the shortest rounding the limits allow is chosen by the
// same dry run.
//
// A new trajectory, mode or experiment takes effect at the first tick not yet planned. New
// parameters (offer_mem_params, or any model's with offer_model) are validated when offered and
// swapped in at the next reversal of the reference, where the inverse's branch restarts, so the
// voltage does not jump. The swap repairs: the plan runs horizon_ticks ahead of the samples, so
// the reversal's measured position arrives after the swap was planned; when the samples of the
// first reanchor_ticks of the new branch have arrived, the feedforward is re-anchored there (the
// mean of y measured - y of the model and of u applied - u of the model over them: output and
// input offsets the inverse works with, loop/feedforward_anchor.hpp), ramped in so that the
// voltage never moves faster than slew_fraction of the slew limit on its account
// (docs/TRACKING.md, "A swap that repairs"). After an experiment the
// plan holds the last voltage (no reference) until the sample of the experiment's end arrives;
// the inverse is then anchored at that measured (u, y), on the branch that began at the
// experiment's last reversal, and the reference approaches from there.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>

#include "core/sequence_gap_detector.hpp"
#include "core/ticks.hpp"
#include "loop/experiment.hpp"
#include "loop/experiment_queue.hpp"
#include "loop/feedforward_anchor.hpp"
#include "loop/hysteresis_inverses.hpp"
#include "loop/periodic_learner.hpp"
#include "loop/scan_path.hpp"
#include "loop/trajectory.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/model_set.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/reversal_detector.hpp"
#include "models/second_order_stage.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// Which feedforward; numbering shared with command_block_t.mode / control_t.mode. A model's mode
// is the number its entry in OnlineModels (models/model_set.hpp) gives it: one added there takes
// the next free one (6, ...) and needs no enumerator here.
enum class FeedforwardMode : std::int8_t {
  kOff = 0,        // no feedforward: u_ff = 0 (the bridge's servo alone)
  kLinear = 1,     // static gain: the MEM paper's "linear feedforward"
  kMem = 2,        // hybrid MEM element inverse (Strijbosch et al., Theorem 10)
  kPi = 3,         // Prandtl-Ishlinskii inverse
  kKatalenic = 4,  // Lambert-W operator inverse
  kExperiment = 5  // identification excitation: raw voltage, no reference (not selectable as a mode)
};

// Parses "off|linear|mem|pi|katalenic"; throws ParameterError naming `field`.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field = "compensator.mode");
// "off, linear, mem, pi or katalenic": the modes a config or SET_MODE may select, in wire order.
std::string selectable_mode_choices();
const char* to_string(FeedforwardMode mode) noexcept;
// The mode that inverts `kind`, and the model a mode inverts (none for off and experiment).
FeedforwardMode mode_of(ModelKind kind) noexcept;
std::optional<ModelKind> model_kind_of(FeedforwardMode mode) noexcept;

// The compensator's learning: line rates of 10 Hz and up, and a robustness filter at 2 kHz (on the
// simulated stage a 50 Hz line learned with 1 kHz stays at 1.2-1.5 nm, with 2 kHz it reaches
// 0.75 nm in 5 periods: bench/tracking_table --scan).
inline LearningConfig default_learning() {
  LearningConfig l;
  l.max_period_s = 0.1;
  l.cutoff_hz = 2000.0;
  return l;
}

// The shortest rounding of a line's corners the compensator chooses with a stage model: two periods
// of its resonance, what neither the stage's model nor the servo knows well (0 without dynamics).
double resonance_corner_s(const StageModel& stage) noexcept;

class Compensator;
class ScanShare;
// Every axis's law takes its share of one path (laws[i] shares[i]), or none does: each share is
// checked first (Compensator::check_scan: throws ParameterError naming the axis, nothing taken),
// then all are applied.
void take_scan_on_every_axis(std::span<Compensator* const> laws, std::span<const ScanShare> shares, double blend_s);

struct CompensatorConfig {
  FeedforwardMode mode = FeedforwardMode::kMem;
  // Every online model's parameters; PI's are the MEM paper's 15 plays.
  ModelParams models{.pi = pi_params_from_mem(MemParams::paper_like(), 15, 250.0)};
  std::int64_t horizon_ticks = 500;  // plan this many ticks ahead of the last sample (50 ms at 10 kHz)
  double dt_s = 1e-4;                // the bridge's tick
  // The actuator as the bridge limits it (ActuatorLimits' defaults): the feedforward is kept in
  // [u_min_V, u_max_V] (counted in u_clamped) and a re-anchoring ramp within the slew limit.
  double u_min_V = -250.0;
  double u_max_V = 250.0;
  double slew_V_per_s = 5.0e4;
  // Re-anchoring after a swap: the offset is measured over this many ticks of the new branch
  // (averages the sensor noise down; 20 ticks = 2 ms) and ramped in over at least
  // reanchor_ramp_ticks, longer when the voltage would otherwise move faster than
  // slew_fraction x the slew limit on its account.
  std::int64_t reanchor_ticks = 20;
  std::int64_t reanchor_ramp_ticks = 200;
  double slew_fraction = 0.05;  // 0.25 V per tick at 5e4 V/s: about what the 1 Hz reference itself needs
  // The input offset the servo held (u applied - u planned) is taken over at most this fast, so
  // the servo's integrator hands it over without a visible error (ki x 0.5 nm / gain ~ 60 V/s).
  double reanchor_u_rate_V_per_s = 50.0;
  // The stage in series with the hysteresis, inverted too (none: the hysteresis inverse alone).
  StageModel stage{};
  // Learning for periodic references (loop/periodic_learner.hpp), by default for line rates of
  // 10 Hz and up: a slower reference (the MEM paper's 1 Hz cosine) is the re-identification's,
  // and what is learned there adds small reversals that start new branches of MEM's memory.
  LearningConfig learning = default_learning();
  // An experiment (the servo off) is planned within plan_slew_fraction of the slew limit; a
  // trajectory, which the servo corrects, is taken only when its feedforward needs at most
  // plan_slew_fraction - servo_slew_reserve of it and stays inside the range. The reserve is the
  // servo's room at the line's fastest ticks: its tick-to-tick response to 1 nm of sensor noise
  // (0.033 V RMS open loop with the default gains, bench/servo_margins) and, where a line starts,
  // the integrator unwinding what it held on the previous one (0.1-0.16 V per tick, measured
  // live; docs/TRACKING.md). 2 % = 0.1 V per tick at 5e4 V/s.
  double plan_slew_fraction = 0.99;
  double servo_slew_reserve = 0.02;
  // The share of the slew limit a tracked line's feedforward may use.
  double tracking_slew_fraction() const noexcept { return plan_slew_fraction - servo_slew_reserve; }
  double tracking_slew_V_per_s() const noexcept { return tracking_slew_fraction() * slew_V_per_s; }

  static constexpr std::int64_t kMaxHorizonTicks = 8000;  // within the bridge's jitter buffer
  void validate() const;                                  // throws ParameterError naming the field
};

struct CompensatorInput {
  std::int64_t seq = 0;  // tick of the sample
  double u_V = 0.0;      // voltage applied at that tick
  double y_m = 0.0;      // measured position
  // The feedforward the bridge applied at that tick (sensor_block_t.u_ff_V): u_V - u_ff_V is what
  // the servo (and any clamp) added, whose share of the position the learning takes out. NaN: not
  // known (the learning then sees the servo's share as part of the error).
  double u_ff_V = std::numeric_limits<double>::quiet_NaN();
};

struct CompensatorCounters {
  std::uint64_t samples = 0;
  std::uint64_t out_of_order = 0;  // samples whose seq did not increase (ignored)
  std::uint64_t gaps = 0;          // missing sample ticks
  std::uint64_t planned = 0;       // command ticks planned
  std::uint64_t ticks_behind = 0;  // ticks the bridge reached before they were planned (never sent)
  std::uint64_t params_accepted = 0;
  std::uint64_t params_rejected = 0;
  std::uint64_t params_swapped = 0;
  std::uint64_t reversals = 0;             // of the planned reference
  std::uint64_t nonfinite_outputs = 0;     // model produced NaN/Inf: the last voltage was held
  std::uint64_t model_switches = 0;        // swaps that changed the model (offer_model)
  std::uint64_t reanchors = 0;             // swaps re-anchored at the measured position
  std::uint64_t reanchors_skipped = 0;     // not re-anchored: the branch ended (or the mode changed) first
  std::uint64_t u_clamped = 0;             // feedforward ticks held inside [u_min_V, u_max_V]
  std::uint64_t u_slew_clamped = 0;        // feedforward ticks held within the slew limit
  std::uint64_t learning_held = 0;         // ticks whose learned correction the limits held back
  std::uint64_t trajectories_refused = 0;  // infeasible (or invalid) trajectories not taken
  std::uint64_t trajectories_shaped = 0;   // taken after shaping to feasibility
  std::uint64_t stage_swaps = 0;           // stage models swapped in
  std::uint64_t experiment_ramped = 0;     // experiment ticks ramped towards the excitation (a jump between two)
};

// What the feedforward of a trajectory needs, from a dry run of the plan.
struct PlanExtent {
  double u_min_V = 0.0;
  double u_max_V = 0.0;
  double rate_max_V_per_s = 0.0;  // largest |u_k - u_{k-1}| / dt
  std::int64_t ticks = 0;         // tracking ticks planned
};

// How a trajectory was taken (set_trajectory).
struct TrajectoryVerdict {
  bool started = true;  // false: a start time was given but had already passed (taken as soon as possible)
  bool shaped = false;  // shaped to feasibility (note says how)
  std::string note;     // the corner chosen, how it was shaped; empty when taken as given
  TrajectorySpec spec;  // what the plan follows
  PlanExtent extent;    // what its feedforward needs
};

class Compensator {
 public:
  explicit Compensator(const CompensatorConfig& config);  // validates

  // A sensor tick, in order. Sets how far the plan must reach. Allocation-, lock-, throw-free.
  void observe(const CompensatorInput& sample) noexcept;
  // Plans the next ticks not yet planned, up to out.size() of them and no further than the
  // horizon after the last sample; returns how many were written (0: the plan is complete).
  std::size_t plan(std::span<CommandTick> out) noexcept;

  // A new reference starting at loop time start_s (NaN or earlier than the next planned tick
  // + blend_s: as soon as possible, approaching from the reference planned last over
  // spec.blend_s). Returns false when a start time was given but already passed. Validated
  // here (throws ParameterError), and checked against the actuator's limits: an infeasible
  // reference throws ParameterError naming the limit and the largest feasible amplitude and
  // frequency, unless spec.shape_if_infeasible, when it is shaped (see take_trajectory).
  bool set_trajectory(TrajectorySpec spec, double start_s);
  // The same, saying how it was taken (the corner chosen, the shaping).
  TrajectoryVerdict take_trajectory(TrajectorySpec spec, double start_s);
  // This axis's share of a multi-axis path (loop/scan_path.hpp: a raster or a Lissajous figure,
  // decoupled by the row of C^{-1} it carries). The path is fixed in loop time, every axis on the
  // same clock: it starts at share.start_s(), which must be at least blend_s after the next tick
  // not yet planned (else ParameterError: the axes would not start together), approached from the
  // reference planned last over blend_s as a trajectory is. Checked by a dry run over the approach
  // and the whole path (refused, never shaped: shaping one axis would tear the path apart; a path
  // ending more than 200,000 ticks ahead, 20 s at 10 kHz, is refused, as is one taken while an
  // experiment runs or waits). After its end the reference holds the path's last point. Learning follows a
  // raster's fast axis when its share is that axis alone (ScanShare::periodic_part); an experiment
  // or a new trajectory ends the scan (a new one fades out its decoupling term over its approach),
  // and so does a restart of the bridge's clock (restarted()). New parameter sets are checked
  // against what is left of the path (offer_model, offer_mem_params).
  TrajectoryVerdict take_scan(const ScanShare& share, double blend_s);
  // take_scan in two steps, for the axes of a stage to take a path together or not at all
  // (take_scan_on_every_axis): check_scan runs every check and the dry run and changes nothing but
  // the refusal counter (throws ParameterError as take_scan does); apply_scan takes a share that
  // check_scan accepted, with the extent it returned, before anything else changed the plan.
  PlanExtent check_scan(const ScanShare& share, double blend_s);
  TrajectoryVerdict apply_scan(const ScanShare& share, double blend_s, const PlanExtent& checked);
  const ScanShare* scan() const noexcept { return scan_ ? &scan_->share : nullptr; }
  // What the plan would need for `spec` from here, without changing anything (a dry run in a copy).
  PlanExtent dry_run(const TrajectorySpec& spec, double start_s) const;
  // The same over its periods only, as if the plan had just entered the shape at rest.
  PlanExtent dry_run_periodic(const TrajectorySpec& spec) const;

  // Learning for periodic references: on/off at run time, and forgetting what was learned.
  void set_learning(bool on) noexcept;
  void reset_learning() noexcept;
  const PeriodicLearner& learner() const noexcept { return learner_; }
  // The stage model in use (kind kNone: the hysteresis inverse alone).
  const StageModel& stage() const noexcept { return stage_model_; }

  // New MEM parameters; validated (throws ParameterError) and swapped at the next reversal,
  // re-anchored; the mode does not change (MEM stays the default: the MEM paper's workflow).
  void offer_mem_params(const MemParams& params, std::int32_t version);
  // A parameter set of any model (models/model_set.hpp), e.g. the online selector's choice.
  // Validated (throws ParameterError naming the field, counted in params_rejected) and swapped
  // in at the next reversal of the reference: the model's parameters are replaced and, unless
  // the mode is off, the feedforward switches to that model, started where the plan is (no
  // step in u) and re-anchored at the measured position as offer_mem_params' sets are. A later
  // offer replaces one still waiting. Not on the per-sample path (may be called between plans).
  // Both refuse (ParameterError, params_rejected) a set under which the periodic line in force
  // would need more of the slew limit than it was admitted at: a refit of other loops can
  // misjudge the slope of this line's, and the bridge would clamp it behind the servo's back.
  void offer_model(const ModelParamSet& params, std::int32_t version);
  void set_mode(FeedforwardMode mode);  // re-initialises that inverse where the plan is
  // Starts the experiment at the next planned tick, or queues it behind the running one.
  // Validated here (throws ParameterError; also when the queue is full, and when the excitation
  // leaves the actuator's range or plan_slew_fraction of its slew limit). A jump between two
  // excitations (or from the tracking voltage) is ramped at that rate.
  void start_experiment(const ExperimentSpec& spec);
  // Ends the running experiment at the next planned tick and drops the queue.
  void stop_experiment() noexcept;

  const CompensatorCounters& counters() const noexcept { return counters_; }
  FeedforwardMode mode() const noexcept { return mode_; }
  const MemParams& mem_params() const noexcept { return inverses_.mem_params(); }
  // The model in use with its parameters (kind follows the mode; MEM when the mode is off).
  ModelParamSet model_params() const noexcept;
  bool params_pending() const noexcept { return pending_.has_value(); }
  // A learned line keeps the set it learned under once it has taken learning.hold_params_after
  // tables and its table is well inside learning.max_correction_m: the tables have learned that
  // set's error, and a new one would only be a step of the error they must learn again. (A set
  // swapped in before the first table restarts the learning's periods at the swap.) A pending
  // set for the model in use waits until learning stops, is reset or the line ends.
  bool params_held_by_learning() const noexcept;
  double anchor_offset_m() const noexcept { return shift_m_; }  // the re-anchoring's output offset
  std::int32_t params_version() const noexcept { return params_version_; }
  bool experiment_running() const noexcept { return experiments_.running(); }
  std::size_t experiments_queued() const noexcept { return experiments_.queued(); }
  const TrajectorySpec& trajectory() const noexcept { return trajectory_; }
  double loop_time(std::int64_t seq) const noexcept { return static_cast<double>(seq) * config_.dt_s; }
  std::int64_t last_seq() const noexcept { return ticks_.started() ? ticks_.last_seq() : -1; }  // -1: none yet
  // First tick not yet planned (-1 before the first sample).
  std::int64_t next_tick() const noexcept { return next_tick_; }
  const CompensatorConfig& config() const noexcept { return config_; }
  // The control law for a bridge that restarted (its tick numbering went back): a new one from
  // `config` with what is in force here — the parameter sets, the tracking mode (an experiment is
  // not one), the reference from its start. A reference the sets now in force make infeasible is
  // not taken again: the new law holds where it starts and `refusal` says why (else it is cleared).
  Compensator restarted(CompensatorConfig config, std::string& refusal) const;

 private:
  // The position the servo's share of the voltage made at this sample [m] (observe, for the learning).
  double servo_share_m(const CompensatorInput& sample) noexcept;
  CommandTick plan_tick(std::int64_t k) noexcept;
  void apply_trajectory(const TrajectorySpec& spec, double start_s, const ScanShare* scan = nullptr) noexcept;
  // dry_run for `spec` with the scan `scan` taken under it (nullptr: none), through the path's end.
  PlanExtent dry_run(const TrajectorySpec& spec, double start_s, const ScanShare* scan) const;
  // The reference at t: what the sensor must read (`sensor_m`: the trajectory plus, during a scan,
  // the axis's own path from its start) and what the inverse aims the axis's own displacement at
  // (`aim_m`: the same plus, during a scan, what the decoupling adds, w_a - r_a, faded in over the
  // approach). The bridge's servo and the learning work on the first, the inverses on the second.
  struct ReferencePoint {
    double sensor_m;
    double aim_m;
  };
  struct ScanInForce;
  static ReferencePoint reference_point(const TrajectorySpec& trajectory, const std::optional<ScanInForce>& scan,
                                        double t_s) noexcept;
  ReferencePoint reference_at(double t_s) const noexcept { return reference_point(trajectory_, scan_, t_s); }
  // The one a new approach fades out.
  ReferencePoint previous_reference_at(double t_s) const noexcept {
    return reference_point(previous_trajectory_, previous_scan_, t_s);
  }
  // The periodic reference learning follows: the trajectory, or a raster's fast triangle.
  const TrajectorySpec& periodic_reference() const noexcept;
  bool feasible(const PlanExtent& e) const noexcept;
  double choose_corner(const TrajectorySpec& spec, std::string& note) const;
  std::string infeasibility(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const;
  std::string limits_left(const PlanExtent& e) const;  // which limit e leaves, and by how much
  // Throws ParameterError when `candidate` swapped in would take the periodic line in force
  // beyond the plan's share of the slew (a dry run in a copy; nothing to check without a line).
  void check_running_line(const ModelParamSet& candidate, bool switch_model) const;
  // offer_model (switch_model) and offer_mem_params: validated, checked, counted, then pending.
  void offer(const ModelParamSet& set, bool switch_model, std::int32_t version);
  double feasible_amplitude(const TrajectorySpec& spec, double start_s, const PlanExtent& e) const;
  void restart_learning(std::int64_t k) noexcept;
  void set_stage(const StageModel& stage) noexcept;
  CommandTick tracking_tick(std::int64_t k) noexcept;
  double feedforward(double y_ref) noexcept;
  void reset_inverse(double y0) noexcept;
  void restart_reference(double t_s, double from_m) noexcept;
  void swap_params(std::int64_t k) noexcept;     // at a reversal: the pending set in, re-anchored
  bool pending_switches_model() const noexcept;  // the pending set (there is one) changes the mode
  // Restarts `mode`'s inverse at this reversal (u_rev, model coordinates) without a step; returns
  // the model's output there.
  double restart_at_reversal(FeedforwardMode mode, double u_rev) noexcept;
  double nominal_slope() const noexcept;  // [m/V] for the re-anchoring ramp when no secant is known

  CompensatorConfig config_;
  FeedforwardMode mode_;
  TrajectorySpec trajectory_{};
  bool trajectory_starts_now_ = true;     // start_s is set at the next planned tick
  bool trajectory_timed_ = false;         // start_s was given: an experiment's end does not move it
  TrajectorySpec previous_trajectory_{};  // the reference a new one's approach fades out
  // A scan in force: trajectory_ is then a hold at the axis's own reference at the path's start
  // (base_m; the approach is the trajectory's), and the path adds its motion from there.
  struct ScanInForce {
    ScanShare share;
    double base_m;
    double blend_s;   // the approach, over which the decoupling's term fades in
    bool lines_over;  // the path's end has been planned (learning stopped there)
  };
  std::optional<ScanInForce> scan_;
  std::optional<ScanInForce> previous_scan_;  // of previous_trajectory_
  bool from_moving_ = false;                  // ... while that approach lasts
  HysteresisInverses inverses_;
  struct Pending {
    ModelParamSet params;
    bool switch_model;  // offer_model: make it the feedforward; offer_mem_params: parameters only
  };
  std::optional<Pending> pending_;
  std::int32_t pending_version_ = 0;
  FeedforwardAnchor anchor_offset_;
  double shift_m_ = 0.0;     // output offset in effect at the last planned tick
  double u_prev_rev_ = 0.0;  // voltage (model coordinates) at the reversal before the last
  std::int32_t params_version_ = 0;
  StageModel stage_model_;
  std::optional<StageInverse> stage_inverse_;
  bool stage_fresh_ = true;  // the stage inverse starts at rest at the next reference
  PeriodicLearner learner_;
  // The stage driven by the servo's share of the voltage (u_V - u_ff_V, times the linear gain):
  // where the servo has moved the stage, which the learning adds back to the measured error.
  std::optional<SecondOrderStage> servo_share_stage_;
  std::int64_t servo_share_seq_ = -1;  // the last sample it was stepped with
  bool learner_restart_ = true;        // the trajectory or its start changed: restart learning at the next tick
  bool learning_room_ = true;          // the trajectory leaves room for learning's corrections (take_trajectory)
  double last_w_ = 0.0;                // the stage-inverted reference last planned (the hysteresis model's target)
  PlanExtent extent_{};                // of the tracking ticks planned (dry runs read it)
  double last_u_wanted_ = std::numeric_limits<double>::quiet_NaN();  // the last tick's u before any clamp
  ExperimentQueue experiments_;
  ReversalDetector reversals_;
  // The experiment's voltage: where its last branch of the hysteresis began, for the anchor.
  ReversalDetector experiment_u_;
  bool in_experiment_ = false;
  double experiment_branch_u_ = 0.0;  // the voltage of its last reversal [V]

  // The samples' numbering. A step back is never a restart here: the service builds a new
  // Compensator when its SequenceGuard confirms one.
  SequenceGapDetector ticks_{SequenceGapDetector::kNeverRestarts};
  std::int64_t next_tick_ = -1;
  std::int64_t plan_end_ = -1;  // last tick the plan must reach
  double last_ref_ = 0.0;       // last reference planned
  double last_u_ = 0.0;         // last voltage planned
  bool inverse_fresh_ = true;   // next reference initialises the inverse
  // After an experiment: hold last_u_ until the sample of tick anchor_tick_ is observed.
  bool awaiting_anchor_ = false;
  std::int64_t anchor_tick_ = 0;
  std::optional<StagePoint> anchor_;  // where the stage is, when it is not virgin
  CompensatorCounters counters_;
};

}  // namespace hystloop
