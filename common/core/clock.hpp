#pragma once
// The project's two clocks, read in one place:
//   wall_utime()    microseconds since the Unix epoch (system_clock): the `utime` stamped on
//                   messages and status, comparable between hosts, may jump when the clock is set;
//   monotonic_ns()  nanoseconds of CLOCK_MONOTONIC: durations, rate limits, costs and time budgets
//                   inside one process; never jumps. It is the clock PeriodicTimer sleeps on
//                   (clock_nanosleep), so a tick's deadline and a cost measured around it agree.
//                   monotonic_s() is the same clock in seconds.
// Algorithms in common/ do not read either: they take time as an argument (or, for the fitters'
// time budget, a FitClock: ident/fit_clock.hpp), so they stay reproducible under test. The one
// reader in common/ is the re-identifier's worker jobs (reident/), which time themselves for the
// status line: instrumentation that no result depends on.

#include <time.h>

#include <chrono>
#include <cstdint>

namespace hystloop {

inline std::int64_t wall_utime() noexcept {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

inline std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline double monotonic_s() noexcept { return 1e-9 * static_cast<double>(monotonic_ns()); }

}  // namespace hystloop
