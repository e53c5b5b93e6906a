#pragma once
// The re-identifier without a connection and without a clock: blocks in, refit decisions
// out, for one axis of the stage (options.axis: x, y or z; a lab runs one process per axis, the
// fits being independent). It owns the OnlineMemEstimator (fed on the calling thread, the "I/O
// thread"), the refit worker, the set in use and the counters. Time is an argument (now_us, any
// monotonic microsecond clock). The blocks are decoded messages; their ticks are walked with
// for_each_tick (lcm/blocks.hpp), so a block is what a sequence of on_sample calls would be.
//
//   HX_SENSOR:      on_sensor_block(block, now_us)        per tick of our axis: on_sample; no allocation, no lock
//   refused block:  on_refused_block(ticks, now_us)       a NaN/out-of-range block poisons the window
//   HX_COMMAND:     on_command_block(block)               the params_version applied to our axis, by tick
//   HX_PARAMS:      on_params(axis, ...)                  a newer valid set for our axis becomes the set in use
//   often (~10 ms): poll(now_us) -> RefitDecision          collects a finished refit, starts the next
//
// A refit starts every refit_period_s once a full window of new samples is there and the
// worker is idle (one job in flight; a refit that overruns the period delays the next).
// Its outcome is adopted only if it was accepted AND judged against the set still in use:
// the same rule as OnlineMemEstimator::adopt(), kept here because the set in use may also
// change from outside (HX_PARAMS), which the estimator's own version does not know about.

#include <cstdint>
#include <limits>
#include <string>

#include "ident/stage_removal.hpp"
#include "core/latency_stats.hpp"
#include "core/sequence_gap_detector.hpp"
#include "ident/online_mem_estimator.hpp"
#include "lcm/blocks.hpp"
#include "reident/params_in_use.hpp"
#include "reident/refit_worker.hpp"
#include "reident/reident_counters.hpp"
#include "reident/options.hpp"

namespace hystloop {

struct RefitDecision {
  // held: accepted while the operator holds the set in use (not adopted, not published)
  enum class Kind : std::uint8_t { none, accepted, refused, superseded, held };
  Kind kind = Kind::none;
  FitStatus status = FitStatus::ok;
  bool fitted = false;  // a fit ran: `candidate` holds fitted parameters
  MemParams candidate{};
  std::int32_t version = 0;              // accepted: the version it is published with
  double holdout_rms_candidate_m = 0.0;  // held-out branch RMS of the candidate
  double holdout_rms_in_use_m = 0.0;
  double fit_residual_rms_m = 0.0;
  std::size_t samples_used = 0;
  std::size_t window_samples = 0;
  double duration_s = 0.0;
};

class ReidentCore {
 public:
  // own_source names our sets on HX_PARAMS ("reident@host"). start_thread = false: tests
  // run the worker's job themselves (worker().run_pending()).
  ReidentCore(const ReidentOptions& options, std::string own_source, bool start_thread = true,
              RefitWorker::OnEvaluated on_evaluated = {});

  // An accepted HX_SENSOR block (check_message passed): every tick of our axis, in order, through
  // on_sample. A block without our axis (fewer axes) is refused whole, as on_refused_block, and
  // counted (sensor_blocks_wrong_axes): false, so that the caller can say so.
  bool on_sensor_block(const sensor_block_t& block, std::int64_t now_us) noexcept;
  // One tick: the applied voltage u_V and the measured y_m feed the estimator, unless the tick
  // is flagged SAFE_STATE or SENSOR_FAULT (skipped and counted); seq gaps are counted.
  void on_sample(const SensorTick& tick, std::int64_t now_us) noexcept;
  // A block the wire check refused (NaN/Inf or absurd values) of about `ticks` ticks (the
  // service's estimate, >= 1): its ticks are no gap, and the window is marked as holding a
  // non-finite sample, so no refit straddles it.
  void on_refused_block(std::int64_t ticks, std::int64_t now_us) noexcept;
  // An accepted HX_COMMAND block: which parameter version the compensator applies to our axis, by
  // tick. A block without our axis says nothing about it: ignored.
  void on_command_block(const command_block_t& block) noexcept;
  // A set on HX_PARAMS for `axis` (mem_params_t.axis). A set for another axis is another
  // re-identifier's: other_axis, counted (params_other_axis) and nothing else (its version is not
  // followed, it is never adopted and never forged, whatever its publisher id). One for our axis
  // goes on as below.
  ParamsOffer on_params(int axis, const MemParams& params, std::int32_t version, std::int64_t publisher_id, bool valid,
                        std::string_view source) noexcept;
  // A set for our axis; ours (our publisher id, in_use().own_publisher_id()) is an echo. A valid
  // set whose gain leaves options().plausibility is not adopted: `invalid`, counted as
  // params_implausible, the reason in implausible_reason().
  ParamsOffer on_params(const MemParams& params, std::int32_t version, std::int64_t publisher_id, bool valid,
                        std::string_view source) noexcept;
  RefitDecision poll(std::int64_t now_us) noexcept;
  // A new reference was requested for our axis (a trajectory or a scan). When the window holds
  // ticks of a reference that moved (another line), it starts again, so that no refit (MEM's or the
  // model choice's) is fitted across two references: the next one waits for a full window of the
  // new; counted (window_restarts), returns true. A window of an experiment (no reference) or a
  // hold is kept: it is the same stage's loops, which the line after it is fitted on.
  bool on_new_reference() noexcept;

  // A version for a refused candidate published as valid = false (--publish-invalid).
  std::int32_t claim_diagnostic_version() noexcept { return in_use_.claim_version(); }
  // Model choice (ModelChooser): a MEM set it switched to becomes the set in use, with its
  // version; while another model is in use, no MEM refit is started (off: MEM refits stop).
  std::int32_t adopt_own_mem(const MemParams& params) noexcept { return in_use_.adopt_own(params); }
  void set_mem_refits(bool on) noexcept { mem_refits_ = on; }
  // Held: refits still run and are judged and counted, but none becomes the set in use (the
  // operator's, or the last one published, stays) until released.
  void hold(bool on) noexcept { held_ = on; }
  bool held() const noexcept { return held_; }
  bool mem_refits() const noexcept { return mem_refits_; }

  // Health, for HX_STATUS.
  bool stale(std::int64_t now_us) const noexcept;  // no sample for longer than stale_after_s
  bool poisoned() const noexcept;                  // the last degraded_after_poisoned windows were all poisoned
  std::int64_t poisoned_streak() const noexcept { return poisoned_streak_; }
  bool seen_samples() const noexcept { return last_sample_us_ >= 0; }
  double seconds_since_sample(std::int64_t now_us) const noexcept;

  const ReidentCounters& counters() noexcept;  // refreshes the estimator's mirrored totals
  void reset_refit_time() noexcept;            // RESET_COUNTERS: the refit-time statistics start again
  const LatencyStats& refit_time() const noexcept { return refit_time_; }  // ns, since start
  double last_refit_s() const noexcept { return last_refit_s_; }
  const ParamsInUse& in_use() const noexcept { return in_use_; }
  // Why the last set on HX_PARAMS counted as params_implausible was refused ("" before any).
  const std::string& implausible_reason() const noexcept { return implausible_reason_; }
  const ReidentOptions& options() const noexcept { return options_; }
  int axis() const noexcept { return options_.axis; }  // 0 x, 1 y, 2 z
  const OnlineMemEstimator& estimator() const noexcept { return estimator_; }
  RefitWorker& worker() noexcept { return worker_; }

 private:
  // A break in the stream: the oldest held sample goes to the estimator with the last measured
  // position, the younger ones a delayed stage holds are dropped (ident/stage_removal.hpp).
  void flush_stage_removal() noexcept;
  RefitDecision decide(const RefitResult& result) noexcept;
  // A set in MEM's domain whose gain leaves options_.plausibility (the reason kept).
  bool implausible(const MemParams& params) noexcept;

  ReidentOptions options_;
  std::size_t axis_;  // options_.axis as the blocks index it
  OnlineMemEstimator estimator_;
  StageRemoval stage_removal_;  // the stage taken out of each sample before the estimator sees it
  ParamsInUse in_use_;
  RefitWorker worker_;
  ReidentCounters counters_;
  LatencyStats refit_time_;
  std::int64_t period_us_;
  std::int64_t stale_after_us_;
  std::int64_t next_refit_us_ = INT64_MIN;
  std::uint64_t fed_at_last_snapshot_ = 0;
  // The samples' numbering. Every step back is a restart: nothing in front of the re-identifier
  // holds blocks for confirmation, and a bridge that restarted numbers from 0 again.
  SequenceGapDetector ticks_{0};
  std::int64_t refused_since_last_ = 0;  // ticks refused on the wire since the last sample (estimated)
  std::int64_t last_sample_us_ = -1;
  // The last tick whose reference moved (a line being tracked): its reference, and the samples the
  // estimator had been fed then (0: none since the start or the last restart).
  double last_ref_m_ = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t moving_ref_fed_ = 0;
  std::int64_t poisoned_streak_ = 0;
  double last_refit_s_ = 0.0;
  bool mem_refits_ = true;
  bool held_ = false;
  std::string implausible_reason_;
};

}  // namespace hystloop
