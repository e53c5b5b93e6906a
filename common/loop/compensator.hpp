#pragma once
// The compensator's control law without I/O or a clock: the planner (loop/feedforward_planner.hpp),
// the admission of references (loop/reference_admission.hpp), the parameter exchange
// (loop/parameter_exchange.hpp) and the learning (loop/periodic_learner.hpp) behind one interface,
// which the services and the simulations use. It runs ahead of the bridge: after
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
#include <optional>
#include <span>
#include <string>

#include "core/ticks.hpp"
#include "loop/compensator_config.hpp"
#include "loop/experiment.hpp"
#include "loop/feedforward_planner.hpp"
#include "loop/periodic_learner.hpp"
#include "loop/scan_path.hpp"
#include "loop/trajectory.hpp"
#include "models/feedforward_mode.hpp"
#include "models/model_set.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

class Compensator;
// Every axis's law takes its share of one path (laws[i] shares[i]), or none does: each share is
// checked first (Compensator::check_scan: throws ParameterError naming the axis, nothing taken),
// then all are applied.
void take_scan_on_every_axis(std::span<Compensator* const> laws, std::span<const ScanShare> shares, double blend_s);

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
  // take_trajectory in two steps, for a service whose plan must go on while a reference is
  // checked (a dry run covers the approach and 1.25 periods: 125,000 ticks for a 0.1 Hz line, and
  // a refusal searches for the largest feasible amplitude with more of them, longer than the
  // horizon the bridge holds). plan_snapshot() copies the plan as it stands; check_trajectory
  // decides on that copy (const, on any thread: throws ParameterError as take_trajectory does);
  // commit_trajectory takes what it decided into this law, where the plan is then (a start time
  // that has passed meanwhile starts as soon as possible, `started` false).
  FeedforwardPlanner plan_snapshot() const { return planner_; }
  static TrajectoryVerdict check_trajectory(const FeedforwardPlanner& snapshot, TrajectorySpec spec, double start_s,
                                            bool learning_enabled);
  TrajectoryVerdict commit_trajectory(TrajectoryVerdict checked, double start_s);
  void count_refused_trajectory() noexcept { ++planner_.counters().plan_refusals; }
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
  const ScanShare* scan() const noexcept { return planner_.scan(); }
  // What the plan would need for `spec` from here, without changing anything (a dry run in a copy).
  PlanExtent dry_run(const TrajectorySpec& spec, double start_s) const;
  // The same over its periods only, as if the plan had just entered the shape at rest.
  PlanExtent dry_run_periodic(const TrajectorySpec& spec) const;

  // Learning for periodic references: on/off at run time, and forgetting what was learned.
  void set_learning(bool on) noexcept;
  void reset_learning() noexcept;
  const PeriodicLearner& learner() const noexcept { return learner_; }
  // The stage model in use (kind kNone: the hysteresis inverse alone).
  const StageModel& stage() const noexcept { return planner_.stage(); }

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
  // excitations (or from the tracking voltage) is ramped at that rate. A multisine is designed
  // here at the tick (prepare_experiment), and its every sample checked against both limits.
  void start_experiment(const ExperimentSpec& spec);
  // Ends the running experiment at the next planned tick and drops the queue.
  void stop_experiment() noexcept;

  const CompensatorCounters& counters() const noexcept { return planner_.counters(); }
  FeedforwardMode mode() const noexcept { return planner_.mode(); }
  const MemParams& mem_params() const noexcept { return planner_.inverses().mem_params(); }
  // The model in use with its parameters (kind follows the mode; MEM when the mode is off).
  ModelParamSet model_params() const noexcept;
  bool params_pending() const noexcept { return planner_.exchange().has_pending(); }
  // A learned line keeps the set it learned under once it has taken learning.hold_params_after
  // tables and its table is well inside learning.max_correction_m: the tables have learned that
  // set's error, and a new one would only be a step of the error they must learn again. (A set
  // swapped in before the first table restarts the learning's periods at the swap.) A pending
  // set for the model in use waits until learning stops, is reset or the line ends.
  bool params_held_by_learning() const noexcept;
  double anchor_offset_m() const noexcept { return planner_.anchor_offset_m(); }  // the re-anchoring's output offset
  std::int32_t params_version() const noexcept { return planner_.exchange().version(); }
  bool experiment_running() const noexcept { return planner_.experiment_running(); }
  std::size_t experiments_queued() const noexcept { return planner_.experiments_queued(); }
  const TrajectorySpec& trajectory() const noexcept { return planner_.trajectory(); }
  double loop_time(std::int64_t seq) const noexcept { return planner_.loop_time(seq); }
  std::int64_t last_seq() const noexcept { return planner_.last_seq(); }  // -1: none yet
  // First tick not yet planned (-1 before the first sample).
  std::int64_t next_tick() const noexcept { return planner_.next_tick(); }
  const CompensatorConfig& config() const noexcept { return planner_.config(); }
  // The control law for a bridge that restarted (its tick numbering went back): a new one from
  // `config` with what is in force here — the parameter sets, the tracking mode (an experiment is
  // not one), the reference from its start. A reference the sets now in force make infeasible is
  // not taken again: the new law holds where it starts and `refusal` says why (else it is cleared).
  Compensator restarted(CompensatorConfig config, std::string& refusal) const;

 private:
  // A prepared multisine's voltage against the actuator's range and slew limit (ParameterError
  // naming the limit).
  void check_multisine(const ExperimentSpec& spec) const;

  // offer_model (switch_model) and offer_mem_params: validated, checked, counted, then waiting.
  void offer(const ModelParamSet& set, bool switch_model, std::int32_t version);

  FeedforwardPlanner planner_;
  PeriodicLearner learner_;
};

}  // namespace hystloop
