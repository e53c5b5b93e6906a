#pragma once
// Runs OnlineMemEstimator::evaluate off the I/O thread: one job in flight at a time, handed
// over without locks. The owner (the I/O thread, which owns the estimator) snapshots the
// estimator straight into the worker's preallocated window, then submit()s; the worker thread
// evaluates and marks the result done; the owner take()s it and release()s the slot.
//
//   owner:   idle() -> estimator.snapshot(job_window()) -> submit(in_use, version)
//            ... later: if (done()) { use result(); release(); }
//   worker:  waits (futex, no spinning) for a submitted job, evaluates, marks it done.
//
// The slot's state is one atomic: idle -> submitted (owner) -> done (worker) -> idle (owner).
// Whoever moves it away from a state owns the slot's data in it, so window and result are
// never touched by both threads at once. No call on the owner side blocks, allocates or
// locks (submit's wake-up is one futex call); evaluate allocates, on the worker thread.
//
// The worker thread runs at nice 10: a refit never competes on equal terms with the I/O thread.
// Without a thread (start_thread = false) nothing runs by itself: run_pending() evaluates on
// the calling thread, so a test drives the same handoff step by step, deterministically.

#include <atomic>
#include <cstdint>
#include <functional>
#include <thread>

#include "ident/online_mem_estimator.hpp"

namespace hystloop {

struct RefitResult {
  MemRefitOutcome outcome;
  double duration_s = 0.0;         // wall time of evaluate() (instrumentation)
  std::uint64_t window_first_seq = 0;
  std::size_t window_samples = 0;  // samples in the evaluated window
};

class RefitWorker {
 public:
  // Told about each result on the worker thread, right after evaluate (e.g. to log a
  // refusal off the I/O thread). Must not throw.
  using OnEvaluated = std::function<void(const RefitResult&)>;

  // `window` comes from OnlineMemEstimator::make_window() (its capacity is the job's).
  RefitWorker(const OnlineMemOptions& options, MemWindow window, bool start_thread = true, OnEvaluated on_evaluated = {});
  ~RefitWorker();  // waits for a running evaluate (time-bounded), then joins
  RefitWorker(const RefitWorker&) = delete;
  RefitWorker& operator=(const RefitWorker&) = delete;

  // Owner side.
  bool idle() const noexcept { return state_.load(std::memory_order_acquire) == kIdle; }
  bool done() const noexcept { return state_.load(std::memory_order_acquire) == kDone; }
  // Writable only while idle(): fill it with OnlineMemEstimator::snapshot.
  MemWindow& job_window() noexcept { return window_; }
  // Hands the window over, to be judged against `in_use` (wire version `version`).
  // Returns false (and does nothing) unless idle().
  bool submit(const MemParams& in_use, std::uint64_t version) noexcept;
  // Readable only while done().
  const RefitResult& result() const noexcept { return result_; }
  // Returns a done slot to idle. False if it was not done.
  bool release() noexcept;

  // Worker side when there is no thread: evaluates a submitted job now. True if it ran one.
  bool run_pending();
  // Blocks until the job in flight is done (tests and shutdown; never on the I/O thread).
  void wait_until_not_submitted() const noexcept;

  bool threaded() const noexcept { return thread_.joinable(); }

 private:
  static constexpr std::uint32_t kIdle = 0, kSubmitted = 1, kDone = 2, kStop = 3;
  static constexpr int kWorkerNice = 10;  // the worker thread's nice value
  void thread_main();
  void evaluate_job();

  OnlineMemOptions options_;
  MemWindow window_;
  MemParams in_use_{};
  std::uint64_t in_use_version_ = 0;
  RefitResult result_;
  OnEvaluated on_evaluated_;
  std::atomic<std::uint32_t> state_{kIdle};
  std::thread thread_;
};

}  // namespace hystloop
