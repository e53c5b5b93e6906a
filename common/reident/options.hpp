#pragma once
// The re-identifier's settings; services/reidentifier/reident_options.hpp reads them from a
// config. The initial parameter set is read from `mem.c1/c2/c3`, the keys the compensator reads
// and hystloop-identify writes (mem: {c1, c2, c3}), so one YAML snippet configures both; the rest is the
// `reidentifier:` section (each key also --set reidentifier.KEY=V):
//
//   reidentifier.axis                      x, y or z: the stage axis this process fits (x). One process per axis:
//                                     the fits are independent; a lab runs one per axis, on any host (--axis)
//   reidentifier.rate_hz                   tick rate of HX_SENSOR [Hz], converts s -> samples (10000)
//   reidentifier.refit_period_s            time between refits [s] (1)
//   reidentifier.window_s                  data fitted per refit [s] (2)
//   reidentifier.capacity_s                samples kept in the estimator's ring [s] (>= window_s; 10)
//   reidentifier.holdout_branches          most recent complete branches held out of the fit (1)
//   reidentifier.min_relative_improvement  held-out RMS must drop by this fraction vs the set in use (0.02)
//   reidentifier.max_residual_rms_m        bound on the fit residual [m] (20e-9)
//   reidentifier.max_solver_time_s         time bound of the nonlinear refinement [s] (0.05)
//   reidentifier.reversal_dead_band_V      reversals of u smaller than this are not branches [V] (servo jitter; 0)
//   reidentifier.publish_invalid           also publish refused candidates, valid = false (false; --publish-invalid)
//   reidentifier.hold                      start holding the set in use: fit and report, publish nothing until
//                                     released (false; hystloop-ctl hold on|off)
//   reidentifier.stale_after_s             DEGRADED when no sample arrived for this long [s] (1)
//   reidentifier.degraded_after_poisoned   DEGRADED when this many windows in a row were poisoned (3)
//   reidentifier.lcm_queue                 HX_SENSOR (and HX_COMMAND) blocks LCM holds before dropping (>= 100; 2000: 2
//   s) reidentifier.models                    online model choice: "off" (MEM refits only, as before),
//                                     "auto" (MEM, PI, Katalenic, linear) or a list "mem,pi,linear" (off)
//   reidentifier.model_margin              a different model must beat the one in use by this fraction of its
//                                     held-out RMS (0.10; OnlineSelectorOptions::margin)
//   reidentifier.model_period_s            time between model selections [s] (5; each fits every candidate)
//   reidentifier.model_decimation          fit every n-th sample of the window (10: 1 kHz of a 10 kHz window)
//   reidentifier.pin_model                 "none" (automatic), or mem|pi|katalenic|linear: no automatic change;
//                                     a kind not in use is fitted and switched to once (hystloop-ctl pin-model)
//   reidentifier.plausible_gain_factor     F: a set (a refit, a model choice, one on HX_PARAMS) whose gain over
//                                     the actuator's range leaves [linear.gain / F, linear.gain * F] is refused
//                                     and counted, never published or adopted (10; models/gain_plausibility.hpp)
//
// The band's nominal gain and range are the keys the compensator reads from the same snippet:
// linear.gain (the stage's mean slope; default the linear model's) and actuator.u_min_V/u_max_V
// (default -250/250 V).

#include <cstdint>

#include "ident/online_mem_estimator.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"
#include "models/mem.hpp"
#include "models/stage_inverse.hpp"
#include "reident/model_chooser.hpp"

namespace hystloop {

struct ReidentOptions {
  MemParams initial{};  // mem.c1, mem.c2, mem.c3
  int axis = 0;         // reidentifier.axis: 0 x, 1 y, 2 z (the blocks' axis index)
  double rate_hz = 10000.0;
  double refit_period_s = 1.0;
  double window_s = 2.0;
  double capacity_s = 10.0;
  bool publish_invalid = false;
  bool hold = false;  // reidentifier.hold
  double stale_after_s = 1.0;
  std::int64_t degraded_after_poisoned = 3;
  std::int64_t lcm_queue = 2000;
  OnlineMemOptions estimator{};     // window/capacity in samples, gates, fit time bound
  ModelChoiceOptions models{};      // reidentifier.models, model_margin, model_period_s, model_decimation, pin_model
  GainPlausibility plausibility{};  // linear.gain, actuator.u_min_V/u_max_V, reidentifier.plausible_gain_factor
  StageModel stage{};               // stage.*: taken out of the samples before they are fitted (none: as measured)
};

}  // namespace hystloop
