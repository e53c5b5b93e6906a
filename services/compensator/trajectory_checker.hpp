#pragma once
// The check of a trajectory off the compensator's I/O thread. That thread plans the bridge's
// commands as the sensor blocks arrive, and the bridge holds only the horizon (50 ms) of them; the
// dry runs that decide a trajectory (Compensator::check_trajectory: the approach and 1.25 periods,
// 125,000 ticks for a 0.1 Hz line, and for a refusal up to 16 more in the search for the largest
// feasible amplitude) took 65 ms on a busy 2-core machine, long enough for the bridge's buffer to
// run dry and its watchdog to take the stage to the safe state. So the check runs here, on a copy
// of the plan (Compensator::plan_snapshot), while the I/O thread goes on planning the reference in
// force; the I/O thread takes the outcome when it is ready (poll, a load of an atomic flag when
// none is) and commits it to the law (Compensator::commit_trajectory) or reports the refusal.
//
// One check runs at a time, and at most one request waits behind it: a newer request replaces
// the waiting one, which is handed back to be answered as superseded (its sender waits for a
// verdict). The I/O thread is the only caller; the worker thread is joined by the destructor
// after the check under way, if any, ends (a dry run is bounded: ReferenceAdmission's
// kDryRunMaxTicks).

#include <atomic>
#include <condition_variable>
#include <stop_token>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "loop/compensator.hpp"

namespace hystloop {

class TrajectoryChecker {
 public:
  struct Request {
    FeedforwardPlanner snapshot;  // the law's plan when the request arrived
    TrajectorySpec spec;
    double start_s = 0.0;  // loop time [s]; NaN: as soon as possible
    bool learning_enabled = true;
    std::int64_t version = 0;  // trajectory_t.version, for the verdict
    int axis = 0;              // the law it is for
    std::uint64_t epoch = 0;   // the service's law epoch (a bridge restart replaces the laws)
  };
  struct Outcome {
    std::optional<TrajectoryVerdict> verdict;  // taken (to commit), or refused:
    std::string refusal;                       // why (ParameterError's text)
    TrajectorySpec spec;                       // as requested
    double start_s = 0.0;
    std::int64_t version = 0;
    int axis = 0;
    std::uint64_t epoch = 0;
  };

  TrajectoryChecker();
  ~TrajectoryChecker();
  TrajectoryChecker(const TrajectoryChecker&) = delete;
  TrajectoryChecker& operator=(const TrajectoryChecker&) = delete;

  // Queues a check; returns the request it replaced (still waiting, never started), if any.
  std::optional<Request> submit(Request request);
  // A finished check, if one is ready. Never waits for one.
  std::optional<Outcome> poll();
  // A check is running or waiting, or an outcome waits to be polled.
  bool busy() const noexcept { return pending_.load(std::memory_order_acquire) > 0; }
  // Waits until an outcome is ready to poll, or nothing is checking or waiting.
  void wait_ready();

 private:
  void run(const std::stop_token& stop);

  mutable std::mutex mutex_;
  std::condition_variable_any wake_;      // a request arrived, or the stop
  std::condition_variable_any finished_;  // a check finished, or an outcome was polled
  std::optional<Request> waiting_;        // the next to check
  std::optional<Outcome> done_;           // the last finished, until polled
  bool running_ = false;
  std::atomic<int> pending_{0};     // requests submitted and outcomes not yet polled
  std::atomic<bool> ready_{false};  // done_ holds an outcome
  std::jthread worker_;             // last: started when everything above exists
};

}  // namespace hystloop
