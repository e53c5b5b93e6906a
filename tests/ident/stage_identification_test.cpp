// The record-to-model steps hystloop-identify --model stage and hystloop.identify_stage share: the
// order's spelling, sigma's degrees of freedom, and the end-of-tick sample moved so that the fitted
// delay is the rig's own.
#include "ident/stage_identification.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "ident/two_mode_stage.hpp"
#include "models/linear_stage.hpp"
#include "models/multisine.hpp"

namespace hystloop {
namespace {

TEST(StageIdentification, OrdersAreNumOverDenOrAuto) {
  StageFitOptions o;
  set_stage_order("3/6", o);
  EXPECT_FALSE(o.auto_order);
  EXPECT_EQ(o.numerator_order, 3);
  EXPECT_EQ(o.denominator_order, 6);
  set_stage_order("auto", o);
  EXPECT_TRUE(o.auto_order);
  set_stage_order("0/1", o);
  EXPECT_FALSE(o.auto_order);
  for (const char* bad : {"4/2", "2/0", "2/4x", "x/4", "2", "", "-1/2", "2//4", "Auto"}) {
    try {
      set_stage_order(bad, o);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const ParameterError& e) {
      EXPECT_EQ(e.field(), "order") << bad;
    }
  }
}

TEST(StageIdentification, SigmaDegreesOfFreedomFollowWhatMeasuredIt) {
  FrequencyResponse f;
  f.realisations = 4;
  f.periods_used = 5;
  f.total_available = true;
  EXPECT_EQ(sigma_degrees_of_freedom(f), 6.0);  // 2 (R - 1) across realisations
  f.total_available = false;
  EXPECT_EQ(sigma_degrees_of_freedom(f), 32.0);  // 2 R (P - 1) across periods
  f.realisations = 2;
  f.total_available = true;
  EXPECT_EQ(sigma_degrees_of_freedom(f), 0.0);  // nu = 2: E[1 / sigma^2] has no mean, sigma taken as exact
}

// A bridge reports y_k at the end of tick k: the start-of-tick record moved one sample earlier.
// The fit then finds the rig's own 1.5 ticks only when told so; taken as start-of-tick data the
// same record reads as half a tick.
TEST(StageIdentification, TheEndOfTickSampleIsTheRigsOwnDelay) {
  const test::TwoModeStage stage;
  MultisineOptions mo;
  mo.period_samples = 2000;
  mo.f_min_Hz = 5.0;
  mo.f_max_Hz = 3000.0;
  mo.periods = 4;
  mo.realisations = 2;
  mo.seed = 9;
  const Multisine m = design_multisine(mo);
  const std::vector<double> y = stage.simulate(m.u_V, 0.01, 3);
  std::vector<double> y_end(y.size());
  for (std::size_t k = 0; k + 1 < y.size(); ++k) y_end[k] = y[k + 1];
  y_end.back() = y[y.size() - 2000];  // periodic: the sample after the last is a period's first
  FrfOptions fo;
  fo.period_samples = 2000;
  fo.periods = 4;
  fo.realisations = 2;
  StageFitOptions o;
  o.zoh_sample_rate_Hz = 1e4;
  set_stage_order("2/4", o);
  const StageIdentification at_end = identify_stage_dynamics(m.u_V, y_end, m.lines, fo, o, true);
  ASSERT_TRUE(at_end.ok()) << at_end.reason();
  EXPECT_NEAR(at_end.fit.delay_s, 150e-6, 1e-6);
  EXPECT_EQ(&at_end.sigma(), &at_end.frf.sigma_total);  // R = 2 measured it (its nu = 2: weights as exact)
  const StageIdentification as_start = identify_stage_dynamics(m.u_V, y_end, m.lines, fo, o, false);
  ASSERT_TRUE(as_start.ok()) << as_start.reason();
  EXPECT_NEAR(as_start.fit.delay_s, 50e-6, 1e-6);

  // How far up the model is known: the record's noise (0.01 of the output) makes the relative bound
  // grow where the gain falls, at the anti-resonance between the modes (~1.85 kHz): the band ends
  // before it and above the lowest mode; asked from above the top line, nothing is known.
  const double known = model_known_to_hz(at_end, 0.7 * 780.0);
  EXPECT_GT(known, 780.0);
  EXPECT_LT(known, 1850.0);
  EXPECT_EQ(model_known_to_hz(at_end, 0.0, 1e9), at_end.frf.frequency_Hz.back());  // no bound: every line
  EXPECT_EQ(model_known_to_hz(at_end, 5000.0), 0.0);

  const StageIdentification none = identify_stage_dynamics(m.u_V, std::vector<double>(10), m.lines, fo, o, true);
  EXPECT_FALSE(none.ok());
  EXPECT_EQ(model_known_to_hz(none, 0.0), 0.0);
  EXPECT_EQ(none.reason().rfind("no frequency response: ", 0), 0u) << none.reason();
}

// Another class of stage: one mode (600 Hz, zeta 0.05), a non-minimum-phase zero at +2.5 kHz and
// 1.3 ticks of delay, no anti-resonance, simulated by the product's own sampled stage. The fit
// finds the zero in the right half-plane and the delay. With no anti-resonance to stop it, the
// known band runs past the mode: with the record's noise at 0.01 of the input (white) through the
// whole band; at 0.1, until the falling gain (-25 dB at 3 kHz) lets the noise reach 30 % of the
// model, above the mode and below the top line.
StageIdentification identify_non_minimum_phase(double noise_sd) {
  const LinearStageSpec truth = LinearStageSpec::zero_pole({{2500.0, 0.0}}, {{-30.0, 600.0}}, 130e-6);
  LinearStageSimulator sim(discretise(truth, 1e-4));
  MultisineOptions mo;
  mo.period_samples = 2000;
  mo.f_min_Hz = 5.0;
  mo.f_max_Hz = 3000.0;
  mo.periods = 4;
  mo.realisations = 3;
  mo.seed = 5;
  const Multisine m = design_multisine(mo);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, noise_sd);
  std::vector<double> y(m.u_V.size());
  sim.reset(m.u_V.front());
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = sim.step(m.u_V[k]) + noise(rng);  // the end of tick k
  FrfOptions fo;
  fo.period_samples = 2000;
  fo.periods = 4;
  fo.realisations = 3;
  fo.transient_periods = 1;
  StageFitOptions o;
  o.zoh_sample_rate_Hz = 1e4;
  set_stage_order("1/2", o);
  return identify_stage_dynamics(m.u_V, y, m.lines, fo, o, true);
}

TEST(StageIdentification, ANonMinimumPhaseStageIsFittedAndKnownPastItsMode) {
  const StageIdentification id = identify_non_minimum_phase(0.01);
  ASSERT_TRUE(id.ok()) << id.reason();
  EXPECT_NEAR(id.fit.delay_s, 130e-6, 3e-6);
  ASSERT_EQ(id.fit.zeros_rad_s.size(), 1u);
  const double two_pi = 2.0 * std::numbers::pi;
  EXPECT_NEAR(id.fit.zeros_rad_s[0].real() / two_pi, 2500.0, 0.05 * 2500.0);  // right half-plane
  EXPECT_NEAR(std::abs(id.fit.zeros_rad_s[0].imag()), 0.0, 1e-6);
  ASSERT_EQ(id.fit.poles_rad_s.size(), 2u);
  EXPECT_NEAR(std::abs(id.fit.poles_rad_s[0]) / two_pi, std::hypot(30.0, 600.0), 0.01 * 600.0);
  EXPECT_EQ(model_known_to_hz(id, 0.7 * 600.0), id.frf.frequency_Hz.back());

  const StageIdentification noisy = identify_non_minimum_phase(0.1);
  ASSERT_TRUE(noisy.ok()) << noisy.reason();
  const double known = model_known_to_hz(noisy, 0.7 * 600.0);
  EXPECT_GT(known, 1.5 * 600.0);
  EXPECT_LT(known, noisy.frf.frequency_Hz.back());
}
}  // namespace
}  // namespace hystloop
