#pragma once
// The re-identifier's online model choice, beside the MEM refit: every
// period_s it copies the estimator's window (on the I/O thread, no allocation) and hands it to its
// own worker thread, which runs propose_model (common/ident/online_model_selector.hpp: fits MEM,
// PI, Katalenic and linear, ranks them on the held-out branch, proposes a change only past the
// margin). The I/O thread collects the proposal in poll():
//
//   model_change                  -> publish on HX_MODEL; the new set is the model in use. While it
//                                    is not MEM, the MEM refits stop (HX_PARAMS stays quiet).
//   refit of a model other than MEM -> publish on HX_MODEL (new parameters of the model in use).
//   refit of MEM                  -> left to the MEM refit (HX_PARAMS, as without model choice).
//   a set whose gain leaves the rig's band (ReidentOptions::plausibility) -> nothing published,
//                                    counted (model_implausible), the reason in last_reason().
//   a set that explains its window more than regime_factor x worse (held-out RMS) than the best
//   fits of the last kRecentFits selections did (their median, at least 1 nm) -> nothing published, counted
//   (model_unsettled): the window holds two regimes, e.g. an identification sine and the line
//   after it, which no one set of the model describes; a set fitted across them (a PI-15 spread
//   over both amplitudes, 10 nm against 1.5 nm) can track the line that follows far worse than
//   the set in use. Every selection's best fit enters the median, so a lasting change of regime
//   (every window fitted worse from now on) is published after kRecentFits - 1 selections.
//
// Pinning (reidentifier.pin_model, hystloop-ctl pin-model): no automatic change. Pinned to the model in
// use, only its parameters are refitted; pinned to another kind, the next selection fits that kind
// and publishes it as the change (its refit, or its start set -- PI-15 / the chord matched to the
// MEM in use -- when the refit does not beat that on the held-out branch), then stays. A selection
// in flight when the service stops is waited for (its fits are time-bounded by their options). Versions come from the
// core (ParamsInUse): one sequence over HX_PARAMS and HX_MODEL, as the compensator's admission expects.
//
// Handoff through a JobSlot (job_slot.hpp), as RefitWorker's: whoever moves the slot's state owns
// the job's data. start_thread = false: run_pending() runs the job on the caller (tests).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ident/online_mem_estimator.hpp"
#include "ident/online_model_selector.hpp"
#include "models/model_set.hpp"
#include "reident/job_slot.hpp"

namespace hystloop {

class ReidentCore;

struct ModelChoiceOptions {
  bool enabled = false;              // reidentifier.models: off = MEM only, as before the model choice
  double period_s = 5.0;             // reidentifier.model_period_s
  std::optional<ModelKind> pinned;   // reidentifier.pin_model (none = automatic)
  OnlineSelectorOptions selector{};  // margin (reidentifier.model_margin), candidates (reidentifier.models)
  double regime_factor = 3.0;        // reidentifier.model_regime_factor (> 1; 0 = off), see above
};

struct ModelDecision {
  enum class Kind : std::uint8_t { none, change, refit };
  Kind kind = Kind::none;
  ModelParamSet params{};
  std::int32_t version = 0;
  ModelProposal proposal{};  // kind != none: the selector's figures (ranking, held-out RMS)
  std::size_t window_samples = 0;
};

class ModelChooser {
 public:
  // implausible: a proposal whose gain left the core's options().plausibility, not published.
  enum Counter : std::size_t {
    selections,
    changes,
    refits,
    kept,
    failed,
    poisoned,
    left_to_mem,
    implausible,
    held,       // a change or refit proposed while the operator holds the set in use: not published
    unsettled,  // a proposal fitted across a change of regime (regime_factor), or before a new
                // reference: not published
    kCounters
  };
  static const char* counter_name(std::size_t i) noexcept;  // "model_selections", ...

  // initial: the model the compensator starts with (MEM from the configuration). window: from
  // OnlineMemEstimator::make_window(), the job's preallocated copy of the estimator's window.
  static constexpr std::size_t kRecentFits = 3;

  ModelChooser(const ModelChoiceOptions& options, const ModelParamSet& initial, MemWindow window,
               bool start_thread = true);
  ~ModelChooser() = default;  // the slot waits for a selection in flight, then joins
  ModelChooser(const ModelChooser&) = delete;
  ModelChooser& operator=(const ModelChooser&) = delete;

  // I/O thread, every ~10 ms: collects a finished selection (publish what it returns) and starts
  // the next one when the period has passed and the core's window is full.
  ModelDecision poll(ReidentCore& core, std::int64_t now_us);
  // hystloop-ctl pin-model: nullopt = automatic choice again.
  void pin(std::optional<ModelKind> kind) noexcept { options_.pinned = kind; }
  std::optional<ModelKind> pinned() const noexcept { return options_.pinned; }
  const ModelParamSet& in_use() const noexcept { return in_use_; }
  bool enabled() const noexcept { return options_.enabled; }
  std::uint64_t count(Counter c) const noexcept { return counters_[c]; }
  const std::string& last_reason() const noexcept { return last_reason_; }  // the last selection's decision

  bool run_pending() { return slot_.run_pending(); }  // no thread: runs a submitted job here
  void wait_until_not_submitted() const noexcept { slot_.wait_until_not_submitted(); }

 private:
  void evaluate_job();
  ModelDecision collect(ReidentCore& core);
  // The median of the recent selections' best held-out RMS [m] (nullopt: fewer than two yet),
  // then `best_m` joins them.
  std::optional<double> recent_median_then_add(double best_m);

  ModelChoiceOptions options_;
  ModelParamSet in_use_;
  // The job (owned by whoever holds the state).
  MemWindow window_;
  ModelParamSet job_in_use_{};
  OnlineSelectorOptions job_options_{};
  bool job_poisoned_ = false;
  ModelProposal result_{};
  double duration_s_ = 0.0;

  std::int64_t next_us_ = INT64_MIN;
  std::uint64_t fed_at_last_ = 0;
  std::string last_reason_;
  std::uint64_t counters_[kCounters]{};
  std::array<double, kRecentFits> recent_best_m_{};  // a ring of the last selections' best held-out RMS
  std::size_t recent_count_ = 0;
  JobSlot slot_;  // last: its thread ends before the job's data above is destroyed
};

}  // namespace hystloop
