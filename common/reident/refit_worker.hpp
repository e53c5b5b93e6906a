#pragma once
// Runs OnlineMemEstimator::evaluate off the I/O thread, one job at a time through a JobSlot
// (job_slot.hpp: lock-free handoff, worker at nice 10). The owner (the I/O thread, which owns
// the estimator) snapshots the estimator straight into the worker's preallocated window, then
// submit()s; the worker evaluates; the owner reads result() once done() and release()s.
//
//   owner:   idle() -> estimator.snapshot(job_window()) -> submit(in_use, version)
//            ... later: if (done()) { use result(); release(); }
//
// With a GainPlausibility, an accepted candidate whose gain leaves the rig's band is turned into a
// refusal (out_of_range, `implausible`, the reason said) on the worker, before it is reported: a
// fit of a plant 1000x too large (a units error) is never published.
// No call on the owner side blocks, allocates or locks; evaluate allocates, on the worker.
// Without a thread (start_thread = false) run_pending() evaluates on the calling thread, so a
// test drives the same handoff step by step, deterministically.

#include <cstdint>
#include <functional>
#include <optional>

#include "ident/online_mem_estimator.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"
#include "reident/job_slot.hpp"

namespace hystloop {

struct RefitResult {
  MemRefitOutcome outcome;
  double duration_s = 0.0;  // wall time of evaluate() (instrumentation)
  std::uint64_t window_first_seq = 0;
  std::size_t window_samples = 0;  // samples in the evaluated window
  bool implausible = false;        // the fit was accepted but its gain left the band: refused
};

class RefitWorker {
 public:
  // Told about each result on the worker thread, right after evaluate (e.g. to log a
  // refusal off the I/O thread). Must not throw.
  using OnEvaluated = std::function<void(const RefitResult&)>;

  // `window` comes from OnlineMemEstimator::make_window() (its capacity is the job's).
  RefitWorker(const OnlineMemOptions& options, MemWindow window, bool start_thread = true,
              OnEvaluated on_evaluated = {}, std::optional<GainPlausibility> plausibility = std::nullopt);
  ~RefitWorker() = default;  // the slot waits for a running evaluate (time-bounded), then joins
  RefitWorker(const RefitWorker&) = delete;
  RefitWorker& operator=(const RefitWorker&) = delete;

  // Owner side.
  bool idle() const noexcept { return slot_.idle(); }
  bool done() const noexcept { return slot_.done(); }
  // Writable only while idle(): fill it with OnlineMemEstimator::snapshot.
  MemWindow& job_window() noexcept { return window_; }
  // Hands the window over, to be judged against `in_use` (wire version `version`).
  // Returns false (and does nothing) unless idle().
  bool submit(const MemParams& in_use, std::uint64_t version) noexcept;
  // Readable only while done().
  const RefitResult& result() const noexcept { return result_; }
  // Returns a done slot to idle. False if it was not done.
  bool release() noexcept { return slot_.release(); }

  // Worker side when there is no thread: evaluates a submitted job now. True if it ran one.
  bool run_pending() { return slot_.run_pending(); }
  // Blocks until the job in flight is done (tests and shutdown; never on the I/O thread).
  void wait_until_not_submitted() const noexcept { slot_.wait_until_not_submitted(); }

  bool threaded() const noexcept { return slot_.threaded(); }

 private:
  void evaluate_job();

  OnlineMemOptions options_;
  MemWindow window_;
  MemParams in_use_{};
  std::uint64_t in_use_version_ = 0;
  RefitResult result_;
  OnEvaluated on_evaluated_;
  std::optional<GainPlausibility> plausibility_;
  JobSlot slot_;  // last: its thread ends before the job's data above is destroyed
};

}  // namespace hystloop
