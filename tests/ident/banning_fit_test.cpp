// Banning's recipe on the simulated stage (Tables 1 and 2) with seeded sensor noise.
#include "ident/banning_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "core/errors.hpp"
#include "ident/banning_experiments.hpp"
#include "models/coleman_hodgdon.hpp"
#include "models/coleman_hodgdon_theory.hpp"
#include "models/loop_features.hpp"

namespace hystloop {
namespace {

double rel(double est, double truth) { return std::abs(est - truth) / std::abs(truth); }

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

// The default plan (357k samples), or under the sanitizer a lighter one (5 Hz loops, whose areas
// the fit corrects for the lag; fewer of them, hence the looser alpha bound there).
BanningPlanOptions test_plan() {
  BanningPlanOptions p;
  if (kSanitized) {
    p.offsets_V = {-100.0, 0.0, 100.0};
    p.small_amplitudes_V = {1.0, 3.0};
    p.amplitudes_V = {50.0, 100.0, 200.0};
    p.hysteresis_frequency_Hz = 5.0;
    p.settle_periods = 10;
    p.frequencies_Hz = {100.0, 800.0, 1400.0, 1650.0, 1720.0, 1800.0, 2100.0, 2800.0};
    p.frequency_measure_s = 0.05;
  }
  return p;
}
const double kAlphaTolerance = kSanitized ? 0.02 : 5e-3;  // measured 6.1e-3 and 1.3e-3 (paper order: 4.0e-3, 7.4e-3)

// Options with a clock that does not run: the Ceres solves end on their tolerances, not on the
// machine's load, so the figures below are the same on every run.
BanningFitOptions fixed_clock(BanningFitOptions o = {}) {
  o.clock = fixed_fit_clock();
  return o;
}

struct Recorded {
  std::vector<BanningExperiment> plan;
  std::vector<std::vector<double>> y;
  std::vector<BanningExperimentData> data;
};

Recorded record(const BanningStageParams& stage, const BanningPlanOptions& plan_options, double noise_m,
                std::uint64_t seed) {
  Recorded r;
  r.plan = plan_banning_experiments(plan_options);
  r.y.reserve(r.plan.size());
  for (std::size_t i = 0; i < r.plan.size(); ++i) r.y.push_back(run_on_stage(stage, r.plan[i], noise_m, seed + i));
  for (std::size_t i = 0; i < r.plan.size(); ++i) {
    const std::size_t m = r.plan[i].measure_begin;
    r.data.push_back({std::span(r.plan[i].u).subspan(m), std::span(r.y[i]).subspan(m), r.plan[i].sample_rate_Hz});
  }
  return r;
}

TEST(BanningFit, SineEstimateReadsOffsetAmplitudeFrequency) {
  std::vector<double> u(1000);
  for (std::size_t k = 0; k < u.size(); ++k)
    u[k] = 3.0 + 2.0 * std::sin(2.0 * std::numbers::pi * 2800.0 * static_cast<double>(k) / 1e4 + 0.3);
  const SineEstimate e = estimate_sine(u, 1e4);
  ASSERT_TRUE(e.ok);
  EXPECT_NEAR(e.frequency_Hz, 2800.0, 1e-3);
  EXPECT_NEAR(e.amplitude, 2.0, 1e-6);
  EXPECT_NEAR(e.offset, 3.0, 1e-6);
}

TEST(BanningFit, ZohMagnitudeMatchesTheSimulatedLinearStage) {
  // Drive the stage alone (no hysteresis) and compare the measured first harmonic.
  const SecondOrderStageParams p{};
  for (double f : {100.0, 1700.0, 2800.0}) {
    SecondOrderStage s(p);
    std::vector<double> y;
    const double w = 2.0 * std::numbers::pi * f;
    for (int k = 0; k < 3000; ++k) {
      const double out = s.step(std::sin(w * k * 1e-4), 1e-4);
      if (k >= 1000) y.push_back(out);
    }
    const double h = first_harmonic_amplitude(y, f, 1e4);
    EXPECT_NEAR(h, stage_magnitude_model(p.k, p.c, w, 1e-4), 1e-6 * h) << f;
  }
  // Continuous vs ZOH differ by ~5 % at the resonance: why the fit models the hold.
  const double wr = std::sqrt(SecondOrderStageParams{}.k);
  EXPECT_GT(rel(stage_magnitude_model(p.k, p.c, wr, 1e-4), stage_magnitude_model(p.k, p.c, wr, 0.0)), 0.01);
}

TEST(BanningFit, RecoversTables1And2FromNoisySimulatedExperiments) {
  const BanningStageParams truth{};
  const Recorded rec = record(truth, test_plan(), 1e-9, 1000);
  const BanningFitResult r = fit_banning(rec.data, fixed_clock());
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_TRUE(r.stage_identified) << r.reason;
  const auto& h = truth.hysteresis;
  std::printf("a %.4g (%.2e)  b %.4g (%.2e)  alpha %.4g (%.2e)  k %.4g (%.2e)  c %.4g (%.2e)  %.1f ms\n",
              r.hysteresis.a, rel(r.hysteresis.a, h.a), r.hysteresis.b, rel(r.hysteresis.b, h.b), r.hysteresis.alpha,
              rel(r.hysteresis.alpha, h.alpha), r.stage.k, rel(r.stage.k, truth.stage.k), r.stage.c,
              rel(r.stage.c, truth.stage.c), r.solve_time_s * 1e3);
  // a from the centre line is nearly noise-free (measured 1.7e-5): 1e-4 (~6x). c is the least
  // determined, by the resonance's width (measured 8.3e-4): 3e-3 (~4x). The data are seeded and the
  // fit's clock fixed, so these figures do not move between runs. (The sanitizer's lighter plan
  // keeps the earlier, wider bounds: not measured here.)
  EXPECT_LT(rel(r.hysteresis.a, h.a), kSanitized ? 2e-3 : 1e-4);
  EXPECT_LT(rel(r.hysteresis.b, h.b), 5e-3);
  EXPECT_LT(rel(r.hysteresis.alpha, h.alpha), kAlphaTolerance);
  EXPECT_LT(rel(r.stage.k, truth.stage.k), 5e-3);
  EXPECT_LT(rel(r.stage.c, truth.stage.c), kSanitized ? 0.03 : 3e-3);
  EXPECT_LT(r.slope_rel_rms, 0.01);
  EXPECT_LT(r.area_rel_rms, kSanitized ? 0.04 : 0.02);
}

TEST(BanningFit, PaperOrderIsRecoveredToo) {
  BanningStageParams truth{};
  truth.order = BanningOrder::kStageThenHysteresis;
  const Recorded rec = record(truth, test_plan(), 1e-9, 2000);
  BanningFitOptions o = fixed_clock();
  o.order = BanningOrder::kStageThenHysteresis;
  const BanningFitResult r = fit_banning(rec.data, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_LT(rel(r.hysteresis.a, truth.hysteresis.a), kSanitized ? 2e-3 : 5e-5);  // measured 6.9e-6: ~7x
  // The CH input is the stage output here, sampled at the step ends: a little looser.
  EXPECT_LT(rel(r.hysteresis.b, truth.hysteresis.b), 1e-2);
  EXPECT_LT(rel(r.hysteresis.alpha, truth.hysteresis.alpha), kAlphaTolerance + 0.01);
  EXPECT_LT(rel(r.stage.k, truth.stage.k), 5e-3);
  EXPECT_LT(rel(r.stage.c, truth.stage.c), 0.05);
  std::printf("paper order: a %.2e b %.2e alpha %.2e k %.2e c %.2e (rel. errors)\n",
              rel(r.hysteresis.a, truth.hysteresis.a), rel(r.hysteresis.b, truth.hysteresis.b),
              rel(r.hysteresis.alpha, truth.hysteresis.alpha), rel(r.stage.k, truth.stage.k),
              rel(r.stage.c, truth.stage.c));
}

// The lag's share of a loop's area: pi a A^2 on the line the loop degenerates to (b == a), and
// on a real loop what a small delay of the output adds to the area extracted from the samples.
TEST(BanningFit, LagAreaIsPiSlopeASquaredOnALineAndWhatADelayAddsToALoop) {
  ColemanHodgdonParams line{};
  line.b = line.a;
  EXPECT_NEAR(loop_lag_area_per_rad(line, 30.0, 50.0), std::numbers::pi * line.a * 50.0 * 50.0,
              1e-6 * std::numbers::pi * line.a * 2500.0);
  const ColemanHodgdonParams h{};
  for (const double amp : {20.0, 100.0}) {
    // Five periods at 4096 samples: w read at theta and at theta - lag.
    constexpr int kPerPeriod = 4096;
    constexpr double kLag = 0.01;  // [rad]
    std::vector<double> u, y_now, y_late;
    ColemanHodgdon now(h), late(h);
    now.reset(-amp), late.reset(-amp);
    for (int k = 0; k < 5 * kPerPeriod; ++k) {
      const double th = 2.0 * std::numbers::pi * k / kPerPeriod;
      u.push_back(-amp * std::cos(th));
      y_now.push_back(now.step(u.back()));
      y_late.push_back(late.step(-amp * std::cos(std::max(0.0, th - kLag))));
    }
    const std::size_t tail = std::size_t{2} * kPerPeriod;  // the last two periods: settled
    const auto span_of = [&](const std::vector<double>& v) { return std::span(v).last(tail); };
    const LoopFeatureResult f0 = extract_loop_features(span_of(u), span_of(y_now));
    const LoopFeatureResult f1 = extract_loop_features(span_of(u), span_of(y_late));
    ASSERT_TRUE(f0.ok() && f1.ok());
    const double added = f1.features.area - f0.features.area;
    EXPECT_NEAR(added, kLag * loop_lag_area_per_rad(h, 0.0, amp), 0.02 * added) << amp;  // first order in the lag
    EXPECT_GT(added, 0.0);
  }
}

// Loops at 5 Hz: the simulated sensor, read at the end of each held sample, is one sample ahead
// of the ZOH model's y[n] = x[n]; less the stage's lag the loops see a 33 us lead, so their
// areas come out ~1 % small and alpha low. The phase fit finds
// that sample and the corrected areas give alpha back.
TEST(BanningFit, FasterLoopsAreCorrectedForTheMeasuredLag) {
  BanningPlanOptions p;
  p.hysteresis_frequency_Hz = 5.0;
  const BanningStageParams truth{};
  const Recorded rec = record(truth, p, 1e-9, 3000);
  const BanningFitResult r = fit_banning(rec.data, fixed_clock());
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_TRUE(r.lag_identified) << r.lag_note;
  EXPECT_NEAR(r.delay_s, -1e-4, 3e-6);
  BanningFitOptions uncorrected = fixed_clock();
  uncorrected.correct_lag = false;
  const BanningFitResult u = fit_banning(rec.data, uncorrected);
  ASSERT_TRUE(u.ok()) << u.reason;
  EXPECT_FALSE(u.lag_identified);
  EXPECT_NE(u.lag_note.find("correct_lag = false"), std::string::npos) << u.lag_note;
  std::printf("5 Hz loops: alpha %.2e corrected, %.2e not; b %.2e, %.2e; delay %.4g us (rel. errors)\n",
              rel(r.hysteresis.alpha, truth.hysteresis.alpha), rel(u.hysteresis.alpha, truth.hysteresis.alpha),
              rel(r.hysteresis.b, truth.hysteresis.b), rel(u.hysteresis.b, truth.hysteresis.b), r.delay_s * 1e6);
  // Seeded data, fixed clock: measured 4.5e-4 corrected, 1.6e-2 not.
  EXPECT_LT(rel(r.hysteresis.alpha, truth.hysteresis.alpha), 2e-3);
  EXPECT_GT(rel(u.hysteresis.alpha, truth.hysteresis.alpha), 1e-2);  // what the correction is for
  EXPECT_LT(rel(r.hysteresis.b, truth.hysteresis.b), 2e-3);
  EXPECT_LT(r.area_rel_rms, 0.01);
  for (const auto& pt : r.points) {
    if (!pt.magnitude_experiment && pt.used) {
      EXPECT_GT(pt.lag_area, 0.0) << pt.amplitude_V;  // a lead: the areas grow back
    }
  }
}

// Without two magnitude experiments below f_n / 2 the lag is not measured: the fit goes on with
// the areas as read, and says so.
TEST(BanningFit, NoSlowMagnitudeExperimentsNoLagCorrection) {
  BanningPlanOptions p = test_plan();
  p.frequencies_Hz = {300.0, 1400.0, 1700.0, 2100.0};
  const Recorded rec = record(BanningStageParams{}, p, 0.0, 7);
  const BanningFitResult r = fit_banning(rec.data, fixed_clock());
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_TRUE(r.stage_identified);
  EXPECT_FALSE(r.lag_identified);
  EXPECT_NE(r.lag_note.find("fewer than 2 magnitude experiments below f_n/2"), std::string::npos) << r.lag_note;
  for (const auto& pt : r.points) EXPECT_EQ(pt.lag_area, 0.0);
}

TEST(BanningFit, RefusalsSayWhy) {
  BanningPlanOptions one_offset;
  one_offset.offsets_V = {0.0};
  one_offset.small_amplitudes_V = {};
  one_offset.amplitudes_V = {};
  one_offset.frequencies_Hz = {};
  const Recorded rec = record(BanningStageParams{}, one_offset, 0.0, 1);
  const BanningFitResult r = fit_banning(rec.data);
  EXPECT_EQ(r.status, FitStatus::too_few_samples) << r.reason;
  EXPECT_NE(r.reason.find("offsets"), std::string::npos) << r.reason;

  std::vector<double> u{0.0, 1.0, 0.0}, y{0.0, std::numeric_limits<double>::quiet_NaN(), 0.0};
  const BanningExperimentData bad[] = {{u, y, 1e4}};
  EXPECT_EQ(fit_banning(bad).status, FitStatus::non_finite_data);
  const BanningExperimentData mismatch[] = {{u, std::span(y).first(2), 1e4}};
  EXPECT_EQ(fit_banning(mismatch).status, FitStatus::size_mismatch);
  // Beyond the sanity bounds (a record scaled by 1e300): refused naming experiment and sample.
  std::vector<double> huge{0.0, 2.5e302, 0.0}, y0{0.0, 1e-9, 0.0};
  const BanningExperimentData scaled[] = {{u, y0, 1e4}, {huge, y0, 1e4}};
  const BanningFitResult h = fit_banning(scaled);
  EXPECT_EQ(h.status, FitStatus::out_of_range) << h.reason;
  EXPECT_NE(h.reason.find("experiment 1: sample 1: u = "), std::string::npos) << h.reason;

  // Hysteresis only (no frequency sweep): ok, but the stage is not identified and it says so.
  BanningPlanOptions no_sweep = test_plan();
  no_sweep.small_amplitudes_V = {2.0};
  no_sweep.amplitudes_V = {100.0};
  no_sweep.hysteresis_frequency_Hz = 5.0;
  no_sweep.frequencies_Hz = {};
  const Recorded rec2 = record(BanningStageParams{}, no_sweep, 0.0, 5);
  const BanningFitResult r2 = fit_banning(rec2.data);
  EXPECT_TRUE(r2.ok()) << r2.reason;
  EXPECT_FALSE(r2.stage_identified);
  EXPECT_FALSE(r2.reason.empty());
}

TEST(BanningFit, InvalidOptionsNameTheField) {
  BanningPlanOptions p;
  p.frequencies_Hz = {6000.0};  // above Nyquist at 10 kHz
  try {
    plan_banning_experiments(p);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "frequencies_Hz");
  }
  BanningFitOptions o;
  o.small_amplitude_max_V = 0.0;
  EXPECT_THROW(fit_banning({}, o), ParameterError);
}

}  // namespace
}  // namespace hystloop
