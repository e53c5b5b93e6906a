#pragma once
// Where the fitters read time, and how every fit ends.
//
// A FitClock gives seconds from an arbitrary origin. The fitters read time only through it: for
// the solver's time budget (max_solver_time_s) and for the result's solve_time_s. By default it
// is the process's monotonic clock (today's behaviour: a refit on a loaded machine stops earlier).
// Pass fixed_fit_clock() (time never passes: only the iteration limits end a solve) or a clock of
// your own, and the same data give the same parameters on any machine.
//
// FitTimer stamps the result: finish() sets status, reason and solve_time_s in one place.

#include <functional>
#include <string>
#include <utility>

#include "core/clock.hpp"
#include "ident/fit_checks.hpp"
#include "ident/fit_status.hpp"

namespace hystloop {

using FitClock = std::function<double()>;  // [s]; empty = monotonic_s()

// Time that never passes: the solvers stop on their iteration and tolerance limits only.
inline FitClock fixed_fit_clock() {
  return [] { return 0.0; };
}

// Status and reason set together (for a step that refuses before the fit is stamped).
template <class Result>
Result with_status(Result r, FitStatus status, const std::string& reason = {}) {
  r.status = status;
  r.reason = reason;
  return r;
}

class FitTimer {
 public:
  explicit FitTimer(const FitClock& clock) : clock_(clock ? clock : FitClock(&monotonic_s)), start_s_(clock_()) {}

  double elapsed_s() const { return clock_() - start_s_; }
  const FitClock& clock() const noexcept { return clock_; }

  // The one way a fitter returns: status, reason and the elapsed time set together.
  template <class Result>
  Result finish(Result r, FitStatus status, std::string reason = {}) const {
    return stamp(with_status(std::move(r), status, std::move(reason)));
  }
  template <class Result>
  Result stamp(Result r) const {
    r.solve_time_s = elapsed_s();
    return r;
  }
  template <class Result>
  Result finish(Result r, FitCheck check) const {
    return finish(std::move(r), check.status, std::move(check.reason));
  }

 private:
  FitClock clock_;
  double start_s_;
};

}  // namespace hystloop
