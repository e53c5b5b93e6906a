#pragma once
// A periodic timer on absolute deadlines: deadline k is start + k * period on
// CLOCK_MONOTONIC, and wait_next() sleeps with clock_nanosleep(TIMER_ABSTIME) to
// the next one, so the work done between two waits does not push the grid.
//
// Overrun policy (no catch-up burst): if the caller comes back after one or more
// later deadlines have already passed, wait_next() returns at once for the LATEST
// deadline that has passed, and the deadlines before it that were never served
// are skipped and counted (TickInfo::skipped, skipped_total()). Lateness is then
// measured against that latest deadline, so it stays below one period; the size
// of the overrun shows in `skipped`. Running the missed ticks back-to-back would
// hand the stage a burst of commands meant for past instants, which is worse than
// holding one tick longer.
//
// The policy itself is DeadlineSchedule, which is pure arithmetic on a given
// "now" and is unit-tested without sleeping; PeriodicTimer adds the clock.

#include <cstdint>

#include "core/clock.hpp"
#include "core/latency_stats.hpp"

namespace hystloop {

// What one wait_next() returned.
struct TickInfo {
  std::uint64_t tick = 0;        // index k of the deadline served (first deadline: 0)
  std::int64_t deadline_ns = 0;  // CLOCK_MONOTONIC time of deadline k
  std::int64_t wake_ns = 0;      // CLOCK_MONOTONIC time the caller was woken
  std::int64_t lateness_ns = 0;  // wake_ns - deadline_ns (>= 0 on Linux)
  std::uint64_t skipped = 0;     // deadlines passed over since the previous tick
};

// Sets how much later than asked the kernel may end the calling thread's timed
// sleeps (prctl PR_SET_TIMERSLACK; default 50'000 ns, ignored for SCHED_FIFO).
// Returns false if refused.
bool set_thread_timer_slack_ns(std::int64_t slack_ns) noexcept;

// Period in ns of a rate in Hz (10'000 Hz -> 100'000 ns). Throws ParameterError
// unless the rate is positive and the period is at least 1 ns.
std::int64_t period_ns_from_rate_hz(double rate_hz);

// Deadline arithmetic of the timer, clock-free.
class DeadlineSchedule {
 public:
  // Deadline k is at first_deadline_ns + k * period_ns. Throws ParameterError
  // ("period_ns") unless period_ns > 0.
  DeadlineSchedule(std::int64_t first_deadline_ns, std::int64_t period_ns);

  // The deadline the next tick is due at.
  std::int64_t next_deadline_ns() const noexcept { return deadline_of(next_tick_); }
  std::uint64_t next_tick() const noexcept { return next_tick_; }
  std::int64_t period_ns() const noexcept { return period_ns_; }
  std::int64_t deadline_of(std::uint64_t tick) const noexcept;

  // The caller woke at `now_ns` (>= next_deadline_ns() normally): serves the
  // latest deadline <= now_ns (never one before next_tick()), counts the ones
  // skipped, and advances. If woken early (now < next deadline), serves the
  // next deadline with a negative lateness.
  TickInfo on_wake(std::int64_t now_ns) noexcept;

  // Moves the grid so that the next tick is due at `next_deadline_ns`; tick
  // indices carry on and nothing is counted as skipped.
  void reanchor(std::int64_t next_deadline_ns) noexcept;

 private:
  std::int64_t first_ns_;
  std::int64_t period_ns_;
  std::uint64_t next_tick_ = 0;
};

class PeriodicTimer {
 public:
  // First deadline one period from now. Throws ParameterError unless period_ns > 0.
  explicit PeriodicTimer(std::int64_t period_ns);
  // First deadline at the given CLOCK_MONOTONIC time.
  PeriodicTimer(std::int64_t period_ns, std::int64_t first_deadline_ns);

  // Sleeps until the next deadline (retrying on EINTR, so a stop request is seen
  // at the latest one period later) and reports the tick. Records the lateness
  // in lateness_stats(). Allocates nothing, throws nothing.
  // The first call sets the calling thread's timer slack to 1 ns (see
  // set_thread_timer_slack_ns): Linux otherwise lets a SCHED_OTHER thread's sleep
  // end up to 50 µs late, half a period at 10 kHz. Call it from one thread.
  TickInfo wait_next() noexcept;

  // Re-anchors the grid: the next deadline is one period from now; tick indices
  // continue. Use after a deliberate pause so it is not counted as skipped ticks.
  void restart() noexcept;

  std::int64_t period_ns() const noexcept { return schedule_.period_ns(); }
  std::uint64_t ticks_served() const noexcept { return served_; }
  std::uint64_t skipped_total() const noexcept { return skipped_; }

  // Lateness of every served tick since construction or the last reset();
  // reset it for per-second windows.
  LatencyStats& lateness_stats() noexcept { return lateness_; }
  const LatencyStats& lateness_stats() const noexcept { return lateness_; }

 private:
  DeadlineSchedule schedule_;
  std::uint64_t served_ = 0;
  std::uint64_t skipped_ = 0;
  LatencyStats lateness_;
};

}  // namespace hystloop
