#include "core/periodic_timer.hpp"

#include <sys/prctl.h>

#include <cerrno>
#include <cmath>
#include <ctime>

#include "core/errors.hpp"

namespace hystloop {
namespace {
constexpr std::int64_t kNsPerS = 1'000'000'000;

timespec to_timespec(std::int64_t ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(ns % kNsPerS);
  return ts;
}
}  // namespace

bool set_thread_timer_slack_ns(std::int64_t slack_ns) noexcept {
  return slack_ns > 0 && ::prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(slack_ns), 0, 0, 0) == 0;
}

std::int64_t period_ns_from_rate_hz(double rate_hz) {
  require_positive("rate_hz", rate_hz);
  const double period = std::round(1e9 / rate_hz);
  if (!(period >= 1.0)) {
    throw ParameterError("rate_hz", "must be <= 1e9 (a period of at least 1 ns)");
  }
  return static_cast<std::int64_t>(period);
}

DeadlineSchedule::DeadlineSchedule(std::int64_t first_deadline_ns, std::int64_t period_ns)
    : first_ns_(first_deadline_ns), period_ns_(period_ns) {
  if (period_ns <= 0) {
    throw ParameterError("period_ns", "must be > 0 (got " + std::to_string(period_ns) + ")");
  }
}

std::int64_t DeadlineSchedule::deadline_of(std::uint64_t tick) const noexcept {
  return first_ns_ + static_cast<std::int64_t>(tick) * period_ns_;
}

TickInfo DeadlineSchedule::on_wake(std::int64_t now_ns) noexcept {
  std::uint64_t tick = next_tick_;
  if (now_ns >= deadline_of(tick)) {
    const auto latest = static_cast<std::uint64_t>((now_ns - first_ns_) / period_ns_);
    if (latest > tick) tick = latest;
  }
  TickInfo info;
  info.tick = tick;
  info.deadline_ns = deadline_of(tick);
  info.wake_ns = now_ns;
  info.lateness_ns = now_ns - info.deadline_ns;
  info.skipped = tick - next_tick_;
  next_tick_ = tick + 1;
  return info;
}

void DeadlineSchedule::reanchor(std::int64_t next_deadline_ns) noexcept {
  first_ns_ = next_deadline_ns - static_cast<std::int64_t>(next_tick_) * period_ns_;
}

PeriodicTimer::PeriodicTimer(std::int64_t period_ns) : PeriodicTimer(period_ns, monotonic_ns() + period_ns) {}

PeriodicTimer::PeriodicTimer(std::int64_t period_ns, std::int64_t first_deadline_ns)
    : schedule_(first_deadline_ns, period_ns) {}

TickInfo PeriodicTimer::wait_next() noexcept {
  if (served_ == 0) (void)set_thread_timer_slack_ns(1);
  const timespec deadline = to_timespec(schedule_.next_deadline_ns());
  // Returns at once if the deadline has passed; EINTR (a signal) sleeps again.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
  const TickInfo info = schedule_.on_wake(monotonic_ns());
  ++served_;
  skipped_ += info.skipped;
  lateness_.add(info.lateness_ns);
  return info;
}

void PeriodicTimer::restart() noexcept { schedule_.reanchor(monotonic_ns() + schedule_.period_ns()); }

}  // namespace hystloop
