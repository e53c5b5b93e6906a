// The simulated stage: CH hysteresis and the second-order stage in series, in both orders.
// Low frequency reduces to the CH loop of Theorem 3; the paper's order obeys (25) exactly and
// (27) approximately; the default order is exact at any sample rate; gain scale; properties.

#include "models/banning_stage.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "models/coleman_hodgdon_theory.hpp"
#include "models/loop_features.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"
#include "support/sanitized.hpp"

namespace hystloop {
namespace {

constexpr double kPi = std::numbers::pi;
using testing::kSanitized;

BanningStageParams with_order(BanningOrder order) {
  BanningStageParams p;
  p.order = order;
  return p;
}

TEST(BanningStageParams, DefaultsAreTables1And2) {
  const BanningStageParams p;
  EXPECT_DOUBLE_EQ(p.hysteresis.a, 8.58e-9);
  EXPECT_DOUBLE_EQ(p.hysteresis.b, 6.07e-9);
  EXPECT_DOUBLE_EQ(p.hysteresis.alpha, 0.0123);
  EXPECT_DOUBLE_EQ(p.stage.k, 1.17e8);
  EXPECT_DOUBLE_EQ(p.stage.c, 2.03e3);
  EXPECT_EQ(p.order, BanningOrder::kHysteresisThenStage);
  const BanningStage stage;
  EXPECT_EQ(stage.gain_scale(), 1.0);
}

TEST(BanningStageParams, ValidationNamesTheFieldWithItsPrefix) {
  BanningStageParams p;
  p.hysteresis.b = 2.0 * p.hysteresis.a;
  const std::optional<ParameterError> e = testing::thrown<ParameterError>([&] { BanningStage s(p); });
  ASSERT_TRUE(e) << "no throw";
  EXPECT_EQ(e->field(), "hysteresis.b");
  EXPECT_EQ(std::string(e->what()).rfind("hysteresis.b: must be in [", 0), 0u) << e->what();
  p = {};
  p.stage.c = -3.0;
  const std::optional<ParameterError> c = testing::thrown<ParameterError>([&] { p.validate(); });
  ASSERT_TRUE(c) << "no throw";
  EXPECT_EQ(c->field(), "stage.c");
  EXPECT_STREQ(c->what(), "stage.c: must be > 0 (got -3)");
}

// At the paper's 2 Hz (Fig. 7) with dt = 100 us, both orders trace the CH loop of Theorem 3:
// the stage is unity gain to 1e-6 there and delays by c / k = 17 us, which moves the features by
// < 0.1 %. Tolerances: centre 0.5 nm, slope 0.1 %, delta/eta/area 0.5 %.
TEST(BanningStage, LowFrequencyLoopIsTheTheorem3Loop) {
  const double dt = 100e-6;
  const int n = 5000;  // 2 Hz
  for (BanningOrder order : {BanningOrder::kHysteresisThenStage, BanningOrder::kStageThenHysteresis}) {
    for (double offset : {0.0, 60.0}) {
      const double amplitude = 100.0;
      BanningStage stage(with_order(order));
      stage.reset(offset);
      std::vector<double> u;
      std::vector<double> y;
      for (int k = 0; k < 8; ++k) {
        for (int i = 0; i < n; ++i) {
          const double ui = offset + amplitude * std::sin(2.0 * kPi * i / n);
          const double yi = stage.step(ui, dt);
          if (k == 7) {
            u.push_back(ui);
            y.push_back(yi);
          }
        }
      }
      const LoopFeatureResult r = extract_loop_features(u, y);
      ASSERT_TRUE(r.ok()) << describe(r.status);
      const LoopFeatures want = exact_loop_features(stage.params().hysteresis, offset, amplitude);
      SCOPED_TRACE(::testing::Message() << "order " << static_cast<int>(order) << " offset " << offset);
      EXPECT_NEAR(r.features.y_centre, want.y_centre, 0.5e-9);
      EXPECT_NEAR(r.features.slope, want.slope, 1e-3 * want.slope);
      EXPECT_NEAR(r.features.delta, want.delta, 5e-3 * want.delta);
      EXPECT_NEAR(r.features.eta, want.eta, 5e-3 * want.eta);
      EXPECT_NEAR(r.features.area, want.area, 5e-3 * want.area);
    }
  }
}

// Stationary peak-to-peak of y under u = A sin(wt), simulated at dt = 2 us (so the CH input's
// reversal between samples is missed by < 6e-5 A and the hold's sinc is > 0.99999).
// f is rounded to a whole number of samples per period.
double stationary_peak_to_peak(BanningOrder order, double& f, double amplitude) {
  const double dt = 2e-6;
  BanningStage stage(with_order(order));
  const auto per = static_cast<int>(std::lround(1.0 / (f * dt)));
  const double f_exact = 1.0 / (per * dt);
  f = f_exact;
  const int periods = std::max(60, static_cast<int>(0.05 * f_exact));  // >= 50 ms: e^{-50} settled
  double lo = HUGE_VAL;
  double hi = -HUGE_VAL;
  for (int k = 0; k < periods; ++k) {
    for (int i = 0; i < per; ++i) {
      const double y = stage.step(amplitude * std::sin(2.0 * kPi * f_exact * i * dt), dt);
      if (k == periods - 1) {
        lo = std::min(lo, y);
        hi = std::max(hi, y);
      }
    }
  }
  return hi - lo;
}

// The paper's order: (25) holds exactly, y_max - y_min = 2 a h A + 2 (b - a) / alpha tanh(alpha A h),
// at any frequency including the resonance (observed 4e-5, tolerance 1e-4: the sampling bound
// above). Estimate (27) h = (y_max - y_min) / (2 b A) is within (a - b) / b (alpha A h)^2 / 3 of h:
// observed 0.23 % at A = 2 V (tolerance 0.3 %), but 3 % to 26 % at A = 40 V. The default order is
// not covered by (25), yet (27) still estimates h to 0.03 % at A = 2 V (observed 2.8e-4 worst over
// the frequencies; tolerance 1e-3, ~3.5x: the (alpha A h)^2 term at A = 2 V is of that order, so a
// factor-of-a-few error in the estimate's bias fails).
TEST(BanningStage, PaperOrderObeysRelation25AndEstimate27) {
  const BanningStageParams p;
  std::printf(
      "  f [Hz]   h(w)   A [V] | pp sim [nm]  pp (25) [nm]   rel | h (27) paper order  rel | "
      "h (27) CH-first  rel\n");
  const std::vector<double> freqs =
      kSanitized ? std::vector<double>{1724.0} : std::vector<double>{200.0, 1000.0, 1500.0, 1724.0};
  for (double f_nominal : freqs) {
    for (double amplitude : {2.0, 40.0}) {
      double f = f_nominal;
      const double pp = stationary_peak_to_peak(BanningOrder::kStageThenHysteresis, f, amplitude);
      const double h = stage_magnitude(p.stage, 2.0 * kPi * f);
      const double want = banning_peak_to_peak(p.hysteresis, h, amplitude);
      const double h27 = magnitude_from_peak_to_peak(pp, p.hysteresis.b, amplitude);
      const double pp_ch = stationary_peak_to_peak(BanningOrder::kHysteresisThenStage, f, amplitude);
      const double h27_ch = magnitude_from_peak_to_peak(pp_ch, p.hysteresis.b, amplitude);
      std::printf("%8.0f %6.3f %6.1f | %11.3f %13.3f %+8.1e | %12.5f %+11.2e | %12.5f %+8.2e\n", f, h, amplitude,
                  pp * 1e9, want * 1e9, pp / want - 1.0, h27, h27 / h - 1.0, h27_ch, h27_ch / h - 1.0);
      EXPECT_NEAR(pp, want, 1e-4 * want) << f << " Hz, " << amplitude << " V";
      if (amplitude <= 2.0) {
        EXPECT_NEAR(h27, h, 3e-3 * h) << f;
        EXPECT_NEAR(h27_ch, h, 1e-3 * h) << f;
      }
    }
  }
}

// Discretisation: with the voltage held over each sample, the default order is exact, so one step
// of 100 us equals 100 steps of 1 us (rounding only: 3e-14 of the peak). The paper's order has the
// Hermite error at y_L's reversals: 2e-9 of the peak at 2 Hz, 5.5e-4 at 1 kHz (2.4e-2 if the CH
// skipped the reversal's extreme). Bounded separately, ~5x and ~2x above what is reached (the
// Hermite error scales with (f dt)^2, so one bound for both would let a 2 Hz error of 1e-3 pass):
// 1e-8 at 2 Hz, 1e-3 at 1 kHz (a regression to skipping the extreme, 2.4e-2, fails).
TEST(BanningStage, DiscretisationAgainstAFinerStep) {
  for (BanningOrder order : {BanningOrder::kHysteresisThenStage, BanningOrder::kStageThenHysteresis}) {
    for (double f : {2.0, 1000.0}) {
      BanningStage coarse(with_order(order));
      BanningStage fine(with_order(order));
      const double dt = 100e-6;
      // Two periods and the transient (a fraction of the 2 Hz period under the sanitizer).
      const int steps = kSanitized ? 500 : static_cast<int>(2.0 / (f * dt)) + 200;
      double worst = 0.0;
      double peak = 0.0;
      for (int i = 0; i < steps; ++i) {
        const double u = 100.0 * std::sin(2.0 * kPi * f * i * dt);
        const double yc = coarse.step(u, dt);
        double yf = 0.0;
        for (int j = 0; j < 100; ++j) yf = fine.step(u, dt / 100.0);
        worst = std::max(worst, std::abs(yc - yf));
        peak = std::max(peak, std::abs(yf));
      }
      std::printf("order %d, %6.0f Hz, A = 100 V: dt = 100 us vs 100 x 1 us: max |error| = %.3g m (%.2g of peak)\n",
                  static_cast<int>(order), f, worst, worst / peak);
      const double paper_bound = f < 10.0 ? 1e-8 : 1e-3;
      EXPECT_LT(worst, (order == BanningOrder::kHysteresisThenStage ? 1e-12 : paper_bound) * peak);
    }
  }
}

TEST(BanningStage, GainScaleMultipliesTheOutputAndRejectsNonsense) {
  BanningStage plain;
  BanningStage warm;
  EXPECT_TRUE(warm.set_gain_scale(1.1));
  for (int i = 0; i < 2000; ++i) {
    const double u = 80.0 * std::sin(0.01 * i);
    const double y = plain.step(u, 1e-4);
    EXPECT_NEAR(warm.step(u, 1e-4), 1.1 * y, 1e-15 * std::abs(y) + 1e-24);
  }
  EXPECT_FALSE(warm.set_gain_scale(0.0));
  EXPECT_FALSE(warm.set_gain_scale(-1.0));
  EXPECT_FALSE(warm.set_gain_scale(std::nan("")));
  EXPECT_FALSE(warm.set_gain_scale(HUGE_VAL));
  EXPECT_DOUBLE_EQ(warm.gain_scale(), 1.1);
  // A warming ramp of +10 % over a minute at 10 kHz is 600000 small changes: state is untouched.
  BanningStage ramped;
  const double y0 = plain.output();
  ramped.reset(0.0);
  plain.reset(0.0);
  for (int i = 1; i <= 1000; ++i) {
    ramped.set_gain_scale(1.0 + 0.1 * i / 1000.0);
    const double u = 50.0 * std::sin(0.02 * i);
    EXPECT_NEAR(ramped.step(u, 1e-4), (1.0 + 0.1 * i / 1000.0) * plain.step(u, 1e-4), 1e-20);
  }
  EXPECT_TRUE(std::isfinite(y0));
}

TEST(BanningStage, ResetIsAnEquilibriumAndBadInputKeepsState) {
  for (BanningOrder order : {BanningOrder::kHysteresisThenStage, BanningOrder::kStageThenHysteresis}) {
    BanningStage stage(with_order(order));
    stage.reset(120.0);
    EXPECT_NEAR(stage.output(), 8.58e-9 * 120.0, 1e-20);
    EXPECT_NEAR(stage.step(120.0, 1e-4), 8.58e-9 * 120.0, 1e-20);  // held input: nothing moves
    stage.step(100.0, 1e-4);
    const double y = stage.output();
    EXPECT_TRUE(std::isnan(stage.step(std::nan(""), 1e-4)));
    EXPECT_TRUE(std::isnan(stage.step(1.0, 0.0)));
    EXPECT_TRUE(std::isnan(stage.step(1.0, std::nan(""))));
    EXPECT_EQ(stage.output(), y);
  }
}

TEST(BanningStage, StepAllocatesNothing) {
  BanningStage a;
  BanningStage b(with_order(BanningOrder::kStageThenHysteresis));
  double sink = 0.0;
  hystloop::testing::AllocationCounter counter;
  for (int i = 0; i < 10000; ++i) {
    a.set_gain_scale(1.0 + 1e-5 * i);
    sink += a.step(200.0 * std::sin(0.003 * i), 1e-4) + b.step(200.0 * std::sin(0.003 * i), 1e-4);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

// Seeded property: random valid parameters in both orders, random inputs within +-s_max and random
// dt. Outputs stay finite and bounded: |y| <= L1 * (a s_max + b / alpha) (CH first) or
// a s_max + b / alpha (stage first), with L1 the stage's impulse-response norm bound.
TEST(BanningStage, PropertyRandomParamsAndInputsStayFiniteAndBounded) {
  std::mt19937_64 rng(20011);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 60; ++trial) {
    BanningStageParams p;
    p.order = trial % 2 == 0 ? BanningOrder::kHysteresisThenStage : BanningOrder::kStageThenHysteresis;
    p.hysteresis.a = 1e-9 * std::pow(10.0, 2.0 * unit(rng));
    p.hysteresis.b = p.hysteresis.a * (0.5 + 0.5 * unit(rng));
    p.hysteresis.alpha = 1e-3 * std::pow(10.0, 2.0 * unit(rng));
    p.hysteresis.s_max = 100.0 + 900.0 * unit(rng);
    p.stage.k = std::pow(10.0, 6.0 + 3.0 * unit(rng));
    p.stage.c = std::sqrt(p.stage.k) * std::pow(10.0, -1.5 + 2.0 * unit(rng));
    BanningStage stage(p);
    ASSERT_TRUE(stage.set_gain_scale(0.5 + unit(rng)));
    const double z = p.stage.damping_ratio();
    const double l1 = z < 1.0 ? 1.0 / (z * std::sqrt(1.0 - z * z)) : 1.0;
    const double ch_bound = p.hysteresis.a * p.hysteresis.s_max + p.hysteresis.b / p.hysteresis.alpha;
    const double bound =
        stage.gain_scale() * (p.order == BanningOrder::kHysteresisThenStage ? l1 * ch_bound : ch_bound);
    // Stage first: keep y_L inside +-s_max by driving within s_max / L1.
    const double u_max = p.order == BanningOrder::kHysteresisThenStage ? p.hysteresis.s_max : p.hysteresis.s_max / l1;
    double dt = 1e-4;
    for (int i = 0; i < 400; ++i) {
      if (i % 50 == 0) dt = std::pow(10.0, -5.5 + 2.0 * unit(rng));
      const double y = stage.step(u_max * (2.0 * unit(rng) - 1.0), dt);
      ASSERT_TRUE(std::isfinite(y));
      ASSERT_LE(std::abs(y), bound * (1.0 + 1e-9)) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace hystloop
