#pragma once
// The compensator's per-tick plan: after each sensor tick k it plans the commands for every tick
// through k + horizon_ticks,
//
//   u_ff(j) = H^-1( y_ref(t_j) ),   y_ref(t_j) = the reference at t_j = j * dt,
//
// one inverse-model step per planned tick, with H^-1 the inverse of the selected hysteresis model
// (and, with a stage model, the stage's exact inverse before or after it). It follows the reference
// it was given (apply_trajectory: a trajectory, or an axis's share of a path), runs identification
// experiments, restarts the reference where an experiment's end was measured, and swaps a waiting
// parameter set in at a reversal (the exchange: loop/parameter_exchange.hpp). What a reference needs
// is recorded in extent() as it is planned, so that a copy of the planner is a dry run
// (loop/reference_admission.hpp).
//
// The learning (loop/periodic_learner.hpp) is not the planner's: the law that owns one lends it to
// plan() and plan_tick(), and a dry run plans without it. Loop time is tick * dt, so the plan is a
// deterministic function of what it was given, in order.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/sequence_gap_detector.hpp"
#include "core/ticks.hpp"
#include "loop/compensator_config.hpp"
#include "loop/experiment.hpp"
#include "loop/experiment_queue.hpp"
#include "loop/hysteresis_inverses.hpp"
#include "loop/parameter_exchange.hpp"
#include "loop/periodic_learner.hpp"
#include "loop/scan_path.hpp"
#include "loop/servo_share.hpp"
#include "loop/swap_review.hpp"
#include "loop/trajectory.hpp"
#include "models/linear_stage.hpp"
#include "models/preview_inverse.hpp"
#include "models/reversal_detector.hpp"
#include "models/second_order_stage.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

class FeedforwardPlanner {
 public:
  explicit FeedforwardPlanner(const CompensatorConfig& config);  // validated by the caller

  // A sensor tick, in order. Sets how far the plan must reach. Returns the position the learning is
  // to observe for that tick (the measurement less the servo's share), or nothing for a sample out
  // of order. Allocation-, lock-, throw-free.
  std::optional<double> observe(const CompensatorInput& sample) noexcept;
  // Plans the next ticks not yet planned, up to out.size() of them and no further than the
  // horizon after the last sample; returns how many were written.
  std::size_t plan(std::span<CommandTick> out, PeriodicLearner* learning) noexcept;
  // Plans tick k (the next one; a dry run plans on in a copy). `learning` may be null.
  CommandTick plan_tick(std::int64_t k, PeriodicLearner* learning) noexcept;

  // The reference from now on (see Compensator::set_trajectory); with `scan`, this axis's share of
  // a path is added to it. Checked by the caller.
  void apply_trajectory(const TrajectorySpec& spec, double start_s, const ScanShare* scan = nullptr) noexcept;
  // The trajectory leaves room for learning's corrections (admission decides).
  void set_learning_room(bool room) noexcept { learning_room_ = room; }
  void set_mode(FeedforwardMode mode) noexcept;  // not kExperiment (checked by the caller)
  void start_experiment(const ExperimentSpec& spec) { experiments_.add(spec); }  // checked by the caller
  void stop_experiment() noexcept { experiments_.stop(loop_time(std::max<std::int64_t>(next_tick_, 0))); }
  void set_stage(const StageModel& stage) noexcept;  // validated by the caller
  // A restarted law takes the parameter sets in force and waiting from `from` (its stage too).
  void carry_params_over(const FeedforwardPlanner& from);

  // For a dry run in a copy: no experiment left, the reference restarted where the plan is
  // (when an experiment ran or its end was awaited), and the extent measured from here.
  void prepare_dry_run() noexcept;
  // For a dry run of `spec`'s periods alone: the plan at the point where the shape is entered, at
  // rest, as if it had been there (no approach).
  void enter_periodic_at_rest(const TrajectorySpec& spec) noexcept;
  void begin_extent() noexcept;
  // For a dry run under `params`: the set swapped in at the next tick, as at a reversal.
  void swap_in_now(const ModelParamSet& params, bool switch_model) noexcept;

  FeedforwardMode mode() const noexcept { return mode_; }
  const CompensatorConfig& config() const noexcept { return config_; }
  const PlanExtent& extent() const noexcept { return extent_; }
  CompensatorCounters& counters() noexcept { return counters_; }
  const CompensatorCounters& counters() const noexcept { return counters_; }
  ParameterExchange& exchange() noexcept { return exchange_; }
  const ParameterExchange& exchange() const noexcept { return exchange_; }
  const HysteresisInverses& inverses() const noexcept { return inverses_; }
  const StageModel& stage() const noexcept { return stage_model_; }
  const TrajectorySpec& trajectory() const noexcept { return trajectory_; }
  const ScanShare* scan() const noexcept { return scan_ ? &scan_->share : nullptr; }
  bool scanning() const noexcept { return scan_ && !scan_->lines_over; }  // a path's lines not yet over
  // The reference starts at the next planned tick (else at trajectory().start_s).
  bool trajectory_starts_now() const noexcept { return trajectory_starts_now_; }
  // An experiment runs, or its end's sample is awaited before tracking resumes.
  bool in_experiment() const noexcept { return in_experiment_ || awaiting_anchor_; }
  bool experiment_running() const noexcept { return experiments_.running(); }
  std::size_t experiments_queued() const noexcept { return experiments_.queued(); }
  double last_ref() const noexcept { return last_ref_; }  // the reference planned last [m]
  double anchor_offset_m() const noexcept { return shift_m_; }
  double loop_time(std::int64_t seq) const noexcept { return static_cast<double>(seq) * config_.dt_s; }
  std::int64_t last_seq() const noexcept { return ticks_.started() ? ticks_.last_seq() : -1; }
  std::int64_t next_tick() const noexcept { return next_tick_; }

 private:
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
  void restart_learning(std::int64_t k, PeriodicLearner& learning) noexcept;
  CommandTick tracking_tick(std::int64_t k, PeriodicLearner* learning) noexcept;
  // The reference of tick k at t: the trajectory started, learning restarted and a path's lines
  // ended where due, the reference before faded out while a new approach lasts.
  ReferencePoint reference_tick(std::int64_t k, double t, PeriodicLearner* learning) noexcept;
  // With a stage inverted with preview (a linear stage): the reference side runs preview_ticks
  // ahead of the commands. plan_reference plans reference tick j (the trajectory, the learning's
  // correction, reversals) and feeds the preview inverse, whose output is the stage input of tick
  // j - preview; preview_tick plans command tick k from what was planned for it.
  struct PlannedReference {
    double y_ref = 0.0;       // the sensor's reference
    double y_aim = 0.0;       // what the inverses aim the axis's own displacement at
    double correction = 0.0;  // the learning's
    double w = 0.0;           // the stage's input for this tick (the hysteresis model's target)
    bool reversal = false;    // of the reference, at this tick
  };
  PlannedReference& ahead(std::int64_t j) noexcept {
    return ahead_[static_cast<std::size_t>(j % static_cast<std::int64_t>(ahead_.size()))];
  }
  void plan_reference(std::int64_t j, PeriodicLearner* learning, bool start_inverse) noexcept;
  CommandTick preview_tick(std::int64_t k, PeriodicLearner* learning) noexcept;
  // The stage input u (after the hysteresis inverse) of tick k made safe, counted and recorded.
  CommandTick command(std::int64_t k, double u, double y_ref, double correction, double w_ref, double shift_V,
                      bool reversal, PeriodicLearner* learning) noexcept;
  double feedforward(double y_ref) noexcept;
  void reset_inverse(double y0) noexcept;
  // A reversal of the reference at tick k: the waiting set swapped in (unless learning holds it).
  void at_reversal(std::int64_t k, PeriodicLearner* learning) noexcept;
  // The inverse starts afresh at y0 (a new mode or reference), the anchor's offsets dropped.
  void restart_inverse(double y0) noexcept;
  void restart_reference(double t_s, double from_m) noexcept;
  void swap_params(std::int64_t k, PeriodicLearner* learning) noexcept;  // at a reversal: the waiting set in
  // Restarts `mode`'s inverse at this reversal (u_rev, model coordinates) without a step; returns
  // the model's output there.
  double restart_at_reversal(FeedforwardMode mode, double u_rev) noexcept;
  double nominal_slope() const noexcept;  // [m/V] for the re-anchoring ramp when no secant is known
  // Tick k's tracking can be held against the ticks before it (SwapReview): a periodic trajectory
  // past its approach and first period, no scan.
  bool comparable_reference(std::int64_t k) const noexcept;
  // What a review of a swap on the line in force spans (no window when the line is not judged).
  SwapReviewSpan review_span() const noexcept;

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
  ParameterExchange exchange_;
  double shift_m_ = 0.0;     // output offset in effect at the last planned tick
  double u_prev_rev_ = 0.0;  // voltage (model coordinates) at the reversal before the last
  StageModel stage_model_;
  std::optional<StageInverse> stage_inverse_;
  bool stage_fresh_ = true;  // the stage inverse starts at rest at the next reference
  // Where the servo's share of the voltage has moved the stage, taken out of what the learning sees.
  ServoShare servo_share_;
  ServoActivity servo_activity_;  // what a learned correction leaves the servo
  // A linear stage: its inverse with preview, and the reference planned ahead of the commands.
  std::optional<PreviewStageInverse> preview_;
  std::int64_t preview_ticks_ = 0;
  std::vector<PlannedReference> ahead_;  // a ring over preview_ticks_ + 1 ticks
  std::int64_t ref_next_ = -1;           // the next reference tick to plan (-1: start at the next command)
  bool learner_restart_ = true;          // the trajectory or its start changed: restart learning at the next tick
  bool learning_room_ = true;            // the trajectory leaves room for learning's corrections
  double last_w_ = 0.0;                  // the stage-inverted reference last planned (the hysteresis model's target)
  PlanExtent extent_{};                  // of the tracking ticks planned (dry runs read it)
  double last_u_wanted_ = std::numeric_limits<double>::quiet_NaN();  // the last tick's u before any clamp
  // Swaps judged by the tracking they give; the set a reviewed swap replaced, taken back when the
  // review finds it tracked better.
  SwapReview review_;
  struct Replaced {
    ModelParamSet params;
    std::int32_t version;
  };
  std::optional<Replaced> replaced_;
  ExperimentQueue experiments_;
  ReversalDetector reversals_;
  // The experiment's voltage: where its last branch of the hysteresis began, for the anchor.
  ReversalDetector experiment_u_;
  bool in_experiment_ = false;
  // Approaching an experiment that starts away from last_u_: at experiment_ramp_V_per_s until the
  // command meets the excitation (then its own voltage, within the plan's slew share).
  bool approaching_ = false;
  double approach_gap_V_ = 0.0;       // the excitation minus the command at the last approach tick
  double experiment_branch_u_ = 0.0;  // the voltage of its last reversal [V]

  // The samples' numbering. A step back is never a restart here: the service builds a new law
  // when its SequenceGuard confirms one.
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
