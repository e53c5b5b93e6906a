#pragma once
// The re-identifier's settings. The initial parameter set is read from `mem.c1/c2/c3`, the
// keys the compensator reads and hystloop-identify writes (mem: {c1, c2, c3}), so one YAML
// snippet configures both; the rest is the `reident:` section (each key also --set reident.KEY=V):
//
//   reident.rate_hz                   tick rate of HX_SENSOR [Hz], converts s -> samples (10000)
//   reident.refit_period_s            time between refits [s] (1)
//   reident.window_s                  data fitted per refit [s] (2)
//   reident.capacity_s                samples kept in the estimator's ring [s] (>= window_s; 10)
//   reident.holdout_branches          most recent complete branches held out of the fit (1)
//   reident.min_relative_improvement  held-out RMS must drop by this fraction vs the set in use (0.02)
//   reident.max_residual_rms_m        bound on the fit residual [m] (20e-9)
//   reident.max_solver_time_s         time bound of the nonlinear refinement [s] (0.05)
//   reident.reversal_dead_band_V      reversals of u smaller than this are not branches [V] (servo jitter; 0)
//   reident.publish_invalid           also publish refused candidates, valid = false (false; --publish-invalid)
//   reident.stale_after_s             DEGRADED when no sample arrived for this long [s] (1)
//   reident.degraded_after_poisoned   DEGRADED when this many windows in a row were poisoned (3)
//   reident.lcm_queue                 HX_SENSOR (and HX_COMMAND) blocks LCM holds before dropping (>= 100; 2000: 2 s)

#include <cstdint>

#include "core/config.hpp"
#include "ident/online_mem_estimator.hpp"
#include "models/mem.hpp"

namespace hystloop {

struct ReidentOptions {
  MemParams initial{};           // mem.c1, mem.c2, mem.c3
  double rate_hz = 10000.0;
  double refit_period_s = 1.0;
  double window_s = 2.0;
  double capacity_s = 10.0;
  bool publish_invalid = false;
  double stale_after_s = 1.0;
  std::int64_t degraded_after_poisoned = 3;
  std::int64_t lcm_queue = 2000;
  OnlineMemOptions estimator{};  // window/capacity in samples, gates, fit time bound
};

// Reads and checks mem.{c1,c2,c3} and reident.*. Unknown reident.* keys are refused ("did
// you mean"); other sections belong to the processes sharing the file (the compensator
// checks the rest of mem.*). Throws ConfigError naming the field.
ReidentOptions read_reident_options(const Config& config);

}  // namespace hystloop
