// Banning et al.'s experiment plan stays inside the actuator's slew limit: a live rig runs it as
// sines (hystloop-ctl experiment --banning-series), and the compensator refuses an excitation the
// actuator could not follow.
#include "ident/banning_experiments.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "core/errors.hpp"

namespace hystloop {
namespace {

double rate_V_per_s(double amplitude_V, double frequency_hz) {
  return 2.0 * std::numbers::pi * amplitude_V * frequency_hz;
}

TEST(BanningExperiments, EverySineOfThePlanFitsTheSlewLimit) {
  for (const double slew : {5.0e4, 4.0e4}) {  // 2 V at 2.8 kHz needs 3.5e4 V/s
    BanningPlanOptions o;
    o.slew_V_per_s = slew;
    int slowed = 0;
    for (const BanningExperiment& e : plan_banning_experiments(o)) {
      EXPECT_LE(rate_V_per_s(e.amplitude_V, e.frequency_Hz), slew) << e.amplitude_V << " V";
      EXPECT_LE(rate_V_per_s(e.amplitude_V, e.settle_frequency_Hz), 0.9 * slew + 1e-6) << e.amplitude_V << " V";
      if (e.kind != BanningExperimentKind::frequency && e.settle_frequency_Hz < o.settle_frequency_Hz) ++slowed;
    }
    EXPECT_GE(slowed, 1) << slew;  // 200 V at 50 Hz would need 6.3e4 V/s: that one settles slower
  }
  BanningPlanOptions too_fast;
  too_fast.frequency_amplitude_V = 5.0;  // 5 V at 2.8 kHz: 8.8e4 V/s
  EXPECT_THROW(plan_banning_experiments(too_fast), ParameterError);
}

}  // namespace
}  // namespace hystloop
