#pragma once
// What the compensator's control law is configured with, what it takes in, what it counts and
// what a dry run of its plan finds: the vocabulary its planner, its reference admission and its
// parameter exchange share (loop/compensator.hpp puts them together).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include "loop/periodic_learner.hpp"
#include "loop/swap_review.hpp"
#include "loop/trajectory.hpp"
#include "models/feedforward_mode.hpp"
#include "models/model_set.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// The compensator's learning: line rates of 10 Hz and up, and a robustness filter at 2 kHz (on the
// simulated stage a 50 Hz line learned with 1 kHz stays at 1.2-1.5 nm, with 2 kHz it reaches
// 0.75 nm in 5 periods: bench/tracking_table --scan).
inline LearningConfig default_learning() {
  LearningConfig l;
  l.max_period_s = 0.1;
  l.cutoff_hz = 2000.0;
  return l;
}

// The learning a law runs beside its stage model. The update assumes the inverse makes the plant
// from correction to position about 1 where its filter passes (loop/periodic_learner.hpp); near a
// lightly damped mode a model a few percent off is not (a mode 10 % off puts |1 - T| near 3 at the
// true resonance), and past an anti-resonance the inverse multiplies what is learned there, the
// sensor noise included, by tens. A linear stage is therefore learned only below
// kLearningShareOfResonance of its lowest lightly damped pole or zero: for a 780 Hz mode up to
// 546 Hz, where the filter is down to 0.22 at the mode, so that a mode 10 % off (|1 - T| up to
// ~3.6 there) keeps Q (1 - gain + gain |1 - T|) below 0.5, inside the update's bound. Measured on
// the two-mode stage with such models (bench/tracking_table --scan --two-mode --wrong-models):
// every line converges, none clamps.
// The configured cutoff stays when it is lower; Banning's second order keeps it (the 2 kHz filter
// converges on it: bench/tracking_table --scan).
inline constexpr double kLearningShareOfResonance = 0.7;
// A stage whose identification measured the model within kStageKnownWithin up to known_to_hz
// (StageModel::known_to_hz) is learned up to this share of that band where it reaches further:
// there the model, not its lowest mode, is what bounds |1 - T|.
inline constexpr double kLearningShareOfKnownBand = 0.7;
LearningConfig learning_for_stage(const LearningConfig& learning, const StageModel& stage, double dt_s);
// The lowest lightly damped (zeta < 0.5) pole or zero of a linear stage [Hz] (0: none, or not a
// linear stage).
double lowest_linear_feature_hz(const StageModel& stage, double dt_s);

// The shortest rounding of a line's corners the compensator chooses with a stage model: two periods
// of its resonance, what neither the stage's model nor the servo knows well (0 without dynamics).
double resonance_corner_s(const StageModel& stage) noexcept;

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
  // An experiment that starts away from where the plan is (another experiment's offset, the
  // tracking voltage) is approached at this rate until the command meets the excitation: a real
  // stage's resonance is not rung by a move at the slew limit. The bridge's safe ramp's default.
  double experiment_ramp_V_per_s = 1.0e3;
  // A set swapped in on a periodic line that tracks it worse than the set before is taken back
  // (loop/swap_review.hpp): a refit judged on its window can still be wrong for the line.
  SwapReviewConfig swap_review{};
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
  // The bridge was in its safe state (sample_flags::kSafeState): u_ff_V is 0 and u_V its ramp to
  // the safe voltage, nothing a servo did.
  bool safe_state = false;
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
  std::uint64_t reversals = 0;            // of the planned reference
  std::uint64_t nonfinite_outputs = 0;    // model produced NaN/Inf: the last voltage was held
  std::uint64_t model_switches = 0;       // swaps that changed the model (offer_model)
  std::uint64_t reanchors = 0;            // swaps re-anchored at the measured position
  std::uint64_t reanchors_skipped = 0;    // not re-anchored: the branch ended (or the mode changed) first
  std::uint64_t u_clamped = 0;            // feedforward ticks held inside [u_min_V, u_max_V]
  std::uint64_t u_slew_clamped = 0;       // feedforward ticks held within the slew limit
  std::uint64_t learning_held = 0;        // ticks whose learned correction the limits held back
  std::uint64_t plan_refusals = 0;        // trajectories and scans the plan refused (outside the limits, invalid)
  std::uint64_t trajectories_shaped = 0;  // taken after shaping to feasibility
  std::uint64_t stage_swaps = 0;          // stage models swapped in
  std::uint64_t experiment_ramped =
      0;  // experiment ticks ramped towards an excitation that starts away (experiment_ramp_V_per_s)
  std::uint64_t swaps_reviewed = 0;    // swaps on a periodic line judged by its tracking (swap_review)
  std::uint64_t swaps_taken_back = 0;  // ... that tracked it worse: the set before swapped in again

  // Every counter with the name the compensator's status gives it. The sum over axes and the
  // status walk this list, and a field above that is not in it fails the static_assert below: no
  // counter is counted and not reported.
  template <class F>
  static constexpr void for_each(F&& f) {
    f("samples", &CompensatorCounters::samples);
    f("out_of_order", &CompensatorCounters::out_of_order);
    f("gaps", &CompensatorCounters::gaps);
    f("planned", &CompensatorCounters::planned);
    f("ticks_behind", &CompensatorCounters::ticks_behind);
    f("params_accepted", &CompensatorCounters::params_accepted);
    f("params_rejected", &CompensatorCounters::params_rejected);
    f("params_swapped", &CompensatorCounters::params_swapped);
    f("reversals", &CompensatorCounters::reversals);
    f("nonfinite_outputs", &CompensatorCounters::nonfinite_outputs);
    f("model_switches", &CompensatorCounters::model_switches);
    f("reanchors", &CompensatorCounters::reanchors);
    f("reanchors_skipped", &CompensatorCounters::reanchors_skipped);
    f("u_clamped", &CompensatorCounters::u_clamped);
    f("u_slew_clamped", &CompensatorCounters::u_slew_clamped);
    f("learning_held", &CompensatorCounters::learning_held);
    f("plan_refusals", &CompensatorCounters::plan_refusals);
    f("trajectories_shaped", &CompensatorCounters::trajectories_shaped);
    f("stage_swaps", &CompensatorCounters::stage_swaps);
    f("experiment_ramped", &CompensatorCounters::experiment_ramped);
    f("swaps_reviewed", &CompensatorCounters::swaps_reviewed);
    f("swaps_taken_back", &CompensatorCounters::swaps_taken_back);
  }
  // The sum over several axes' laws.
  CompensatorCounters& operator+=(const CompensatorCounters& b) noexcept {
    for_each([&](const char*, auto field) { this->*field += b.*field; });
    return *this;
  }
};
inline constexpr std::size_t kCompensatorCounterCount = [] {
  std::size_t n = 0;
  CompensatorCounters::for_each([&](const char*, auto) { ++n; });
  return n;
}();
static_assert(sizeof(CompensatorCounters) == kCompensatorCounterCount * sizeof(std::uint64_t),
              "a counter of CompensatorCounters is missing from for_each");

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

}  // namespace hystloop
