#pragma once
// The project's two clocks, read in one place:
//   wall_utime()   microseconds since the Unix epoch (system_clock): the `utime` stamped on
//                  messages and status, comparable between hosts, may jump when the clock is set;
//   monotonic_s()  seconds since an arbitrary origin (steady_clock): durations, rate limits and
//                  time budgets inside one process; never jumps. monotonic_ns() is the same clock
//                  in nanoseconds, for costs and rate limiters counted in integers.
// Algorithms in common/ do not read either: they take time as an argument (or, for the fitters'
// time budget, a FitClock: ident/fit_clock.hpp), so they stay reproducible under test.

#include <chrono>
#include <cstdint>

namespace hystloop {

inline std::int64_t wall_utime() noexcept {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

inline std::int64_t monotonic_ns() noexcept {
  using namespace std::chrono;
  return duration_cast<nanoseconds>(steady_clock::now().time_since_epoch()).count();
}

inline double monotonic_s() noexcept {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

}  // namespace hystloop
