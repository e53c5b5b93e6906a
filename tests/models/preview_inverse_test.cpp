#include "models/preview_inverse.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using Mode = LinearStageSpec::Mode;
constexpr double kDt = 1e-4;  // the bridge's tick
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::int64_t kPreview = 500;  // the compensator's 50 ms

const std::vector<Mode> kTwoModes{{780.0, 0.03, 0.7}, {2400.0, 0.02, 0.3}};

// offset + amplitude * (five random sines below 500 Hz, seeded) / (sum of their weights), faded in
// with a raised cosine after `rest` ticks at the offset (so that the preview is consistent with
// the reset), n ticks long.
std::vector<double> smooth_reference(std::uint64_t seed, double amplitude, double offset, int rest, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> freq(5.0, 500.0), phase(0.0, kTwoPi), weight(0.2, 1.0);
  double f[5], p[5], a[5], total = 0.0;
  for (int i = 0; i < 5; ++i) {
    f[i] = freq(rng);
    p[i] = phase(rng);
    a[i] = weight(rng);
    total += a[i];
  }
  constexpr int kFade = 1000;
  std::vector<double> r(static_cast<std::size_t>(n), offset);
  for (int k = rest; k < n; ++k) {
    const double t = (k - rest) * kDt;
    const double fade = k - rest >= kFade ? 1.0 : 0.5 - 0.5 * std::cos(std::numbers::pi * (k - rest) / kFade);
    double v = 0.0;
    for (int i = 0; i < 5; ++i) v += a[i] * (std::sin(kTwoPi * f[i] * t + p[i]) - std::sin(p[i]));
    r[static_cast<std::size_t>(k)] = offset + fade * amplitude * v / total;
  }
  return r;
}

// The stage driven by the inverse: the worst |y_k - r_k| over every tick.
double worst_tracking_error(const DiscreteLinearStage& stage, std::int64_t preview, std::uint64_t seed) {
  const int n = 12000;
  const std::vector<double> r = smooth_reference(seed, 1e-6, 0.2e-6, static_cast<int>(preview) + 1, n);
  PreviewStageInverse inverse(stage, preview);
  LinearStageSimulator sim(stage);
  inverse.reset(r[0]);
  sim.reset(r[0]);
  double worst = 0.0;
  for (int k = 0; k + preview < n; ++k) {
    const double w = inverse.step(r[static_cast<std::size_t>(k + preview)]);
    const double y = sim.step(w);
    worst = std::max(worst, std::abs(y - r[static_cast<std::size_t>(k)]));
  }
  return worst;
}

TEST(PreviewStageInverse, MinimumPhaseSecondOrderStageReproducesTheReference) {
  const DiscreteLinearStage stage = discretise(LinearStageSpec::second_order(1.17e8, 2.03e3), kDt);
  const PreviewStageInverse inverse(stage, kPreview);
  EXPECT_EQ(inverse.outside_zeros(), 0);
  EXPECT_EQ(inverse.anticausal_taps(), 1);
  EXPECT_EQ(inverse.truncation_error_bound(), 0.0);
  for (const std::uint64_t seed : {1u, 2u, 3u}) EXPECT_LT(worst_tracking_error(stage, kPreview, seed), 1e-9 * 1.2e-6);
}

TEST(PreviewStageInverse, TwoLightlyDampedModesWithAFractionalDelayReproduceTheReference) {
  for (const double delay_ticks : {1.5, 3.0, 0.25, 0.75}) {
    const DiscreteLinearStage stage = discretise(LinearStageSpec::sum_of_modes(kTwoModes, delay_ticks * kDt), kDt);
    const PreviewStageInverse inverse(stage, kPreview);
    EXPECT_LE(inverse.truncation_error_bound(), 1e-15) << delay_ticks;
    for (const std::uint64_t seed : {4u, 5u}) {
      EXPECT_LT(worst_tracking_error(stage, kPreview, seed), 1e-9 * 1.2e-6) << delay_ticks << " ticks, seed " << seed;
    }
  }
}

TEST(PreviewStageInverse, ANonMinimumPhaseStageReproducesTheReferenceFromItsPreview) {
  // A right-half-plane zero at 3 kHz before a 1 kHz mode and a 2 kHz pole: sampled, z = 8.59.
  const DiscreteLinearStage stage =
      discretise(LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-100.0, 995.0}, {-2000.0, 0.0}}), kDt);
  const PreviewStageInverse inverse(stage, kPreview);
  EXPECT_EQ(inverse.outside_zeros(), 1);
  EXPECT_LE(inverse.truncation_error_bound(), 1e-15);
  EXPECT_LT(inverse.anticausal_taps(), 40);  // |1 / 8.59|^j reaches 1e-17 after 19 taps
  for (const std::uint64_t seed : {6u, 7u}) EXPECT_LT(worst_tracking_error(stage, kPreview, seed), 1e-9 * 1.2e-6);
  // Causal inversion is not enough: without preview the same stage is refused.
  EXPECT_EQ(testing::refused_field([&] { PreviewStageInverse(stage, 0); }), "preview_ticks");
}

TEST(PreviewStageInverse, TwoZerosOutsideTheUnitCircleAreInvertedFromThePreview) {
  // (1 - 2 z^-1)(1 - 3 z^-1) / (1 - 0.5 z^-1): the series decays like 2^-j; 1e-17 needs ~57 taps.
  const DiscreteLinearStage stage = discretise(LinearStageSpec::discrete({1.0, -5.0, 6.0}, {1.0, -0.5}, kDt), kDt);
  const PreviewStageInverse inverse(stage, kPreview);
  EXPECT_EQ(inverse.outside_zeros(), 2);
  EXPECT_GE(inverse.anticausal_taps(), 50);
  EXPECT_LE(inverse.anticausal_taps(), 65);
  EXPECT_LE(inverse.truncation_error_bound(), 1e-16);
  EXPECT_LT(worst_tracking_error(stage, kPreview, 10), 1e-9 * 1.2e-6);
  EXPECT_EQ(testing::refused_field([&] { PreviewStageInverse(stage, 1); }), "preview_ticks");  // 2 at least
}

TEST(PreviewStageInverse, TheTruncationBoundFallsWithThePreviewAndAShortPreviewIsRefused) {
  // A zero at z = 1.2: the anti-causal series decays like (1 / 1.2)^j, 1e-12 after about 150 ticks.
  const DiscreteLinearStage stage = discretise(LinearStageSpec::discrete({1.0, -1.2}, {1.0, -0.5}, kDt), kDt);
  double previous = 1.0;
  for (const std::int64_t n : {155, 170, 185, 200}) {
    const PreviewStageInverse inverse(stage, n);
    EXPECT_EQ(inverse.anticausal_taps(), n);  // every tick of the preview is used
    EXPECT_LT(inverse.truncation_error_bound(), previous) << n;
    EXPECT_LE(inverse.truncation_error_bound(), PreviewStageInverse::kMaxTruncationError) << n;
    EXPECT_NEAR(inverse.truncation_error_bound(), std::pow(1.0 / 1.2, n), 0.5 * std::pow(1.0 / 1.2, n)) << n;
    previous = inverse.truncation_error_bound();
  }
  // A longer preview than needed stops at 1e-17.
  EXPECT_LT(PreviewStageInverse(stage, 500).anticausal_taps(), 230);
  try {
    PreviewStageInverse inverse(stage, 100);
    FAIL() << "accepted a preview of 100 ticks, bound " << inverse.truncation_error_bound();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "preview_ticks");
    EXPECT_NE(std::string(e.what()).find("need about 154 ticks of preview"), std::string::npos) << e.what();
  }
  // The delay takes its ticks from the preview.
  const DiscreteLinearStage delayed = discretise(LinearStageSpec::sum_of_modes(kTwoModes, 40.0 * kDt), kDt);
  EXPECT_EQ(testing::refused_field([&] { PreviewStageInverse(delayed, 39); }), "preview_ticks");
  EXPECT_NO_THROW(PreviewStageInverse(delayed, 40));
  EXPECT_EQ(testing::refused_field([&] { PreviewStageInverse(delayed, -1); }), "preview_ticks");
  EXPECT_EQ(testing::refused_field([&] { PreviewStageInverse(delayed, 100000); }), "preview_ticks");
}

TEST(PreviewStageInverse, RefusesAZeroOnTheUnitCircle) {
  const DiscreteLinearStage stage = discretise(LinearStageSpec::discrete({1.0, 1.0}, {1.0, -0.5}, kDt), kDt);
  try {
    PreviewStageInverse inverse(stage, kPreview);
    FAIL() << "accepted a zero at -1";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "stage");
    EXPECT_NE(std::string(e.what()).find("unit circle"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5000 Hz"), std::string::npos) << e.what();
  }
}

TEST(PreviewStageInverse, AtHalfTheTickRateTheInputIsTheInverseGainTimesTheReference) {
  // A sampling zero at -0.99: the inverse multiplies what the reference has at 5 kHz by |1 / G(-1)|
  // = 1.5 * 1.99 / (0.01 * 0.5) = 597.
  const DiscreteLinearStage stage = discretise(LinearStageSpec::discrete({1.0, 0.99}, {1.0, -0.5}, kDt), kDt);
  PreviewStageInverse inverse(stage, 10);
  const double gain = inverse.gain(5000.0);
  EXPECT_NEAR(gain, 597.0, 1e-6);
  double late = 0.0;
  for (int k = 0; k < 6000; ++k) {
    const double w = inverse.step(k % 2 == 0 ? 1e-9 : -1e-9);
    ASSERT_TRUE(std::isfinite(w));
    if (k > 4000) late = std::max(late, std::abs(w));
  }
  EXPECT_NEAR(late, gain * 1e-9, 1e-3 * gain * 1e-9);
}

TEST(PreviewStageInverse, WithTheLowPassTheStageReproducesTheFilteredReference) {
  const DiscreteLinearStage stage = discretise(LinearStageSpec::sum_of_modes(kTwoModes, 1.5 * kDt), kDt);
  const PreviewStageInverse inverse0(stage, kPreview, 300.0);
  const std::span<const double> g = inverse0.reference_lowpass();
  const int m = static_cast<int>(g.size() / 2);
  ASSERT_EQ(m, 134);  // ceil(4 / (300 Hz * 1e-4 s))
  double sum = 0.0;
  for (int j = 0; j < m; ++j) EXPECT_EQ(g[static_cast<std::size_t>(j)], g[static_cast<std::size_t>(2 * m - j)]);
  for (const double v : g) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-15);
  auto response = [&](double hz) {  // zero phase: real
    double h = 0.0;
    for (std::size_t i = 0; i < g.size(); ++i) h += g[i] * std::cos(kTwoPi * hz * (static_cast<int>(i) - m) * kDt);
    return h;
  };
  EXPECT_NEAR(response(0.5 * 300.0), 1.0, 1e-3);
  EXPECT_NEAR(response(300.0), 0.5, 0.01);
  for (double hz = 1.5 * 300.0; hz <= 5000.0; hz += 7.0) EXPECT_LT(std::abs(response(hz)), 2e-4) << hz;
  EXPECT_LE(inverse0.truncation_error_bound(), 1e-15);
  // The filtered reference, computed here: r before tick 0 is r_0.
  const int n = 12000;
  const std::vector<double> r = smooth_reference(8, 1e-6, 0.2e-6, static_cast<int>(kPreview) + m + 1, n);
  auto at = [&](int k) { return r[static_cast<std::size_t>(std::max(0, k))]; };
  PreviewStageInverse inverse(stage, kPreview, 300.0);
  LinearStageSimulator sim(stage);
  inverse.reset(r[0]);
  sim.reset(r[0]);
  double worst = 0.0, worst_unfiltered = 0.0;
  for (int k = 0; k + kPreview < n; ++k) {
    const double y = sim.step(inverse.step(r[static_cast<std::size_t>(k + kPreview)]));
    double filtered = 0.0;
    for (std::size_t i = 0; i < g.size(); ++i) filtered += g[i] * at(k + static_cast<int>(i) - m);
    worst = std::max(worst, std::abs(y - filtered));
    worst_unfiltered = std::max(worst_unfiltered, std::abs(y - at(k)));
  }
  EXPECT_LT(worst, 1e-9 * 1.2e-6);
  EXPECT_GT(worst_unfiltered, 1e-2 * 1.2e-6);  // the reference has content up to 500 Hz
}

TEST(PreviewStageInverse, TheLowPassKeepsTheInverseFromAmplifyingContentNearHalfTheTickRate) {
  // The delay-free two-mode stage: |1 / G| is 323 at 5 kHz. A 4.95 kHz sine in the reference:
  const DiscreteLinearStage stage = discretise(LinearStageSpec::sum_of_modes(kTwoModes), kDt);
  auto late_input = [&](double bandwidth_hz) {
    PreviewStageInverse inverse(stage, kPreview, bandwidth_hz);
    double late = 0.0;
    for (int k = 0; k < 4000; ++k) {
      const double w = inverse.step(1e-9 * std::sin(kTwoPi * 4950.0 * k * kDt));
      if (k > 2000) late = std::max(late, std::abs(w));
    }
    return late;
  };
  const double gain = PreviewStageInverse(stage, kPreview).gain(4950.0);
  EXPECT_GT(gain, 100.0);
  EXPECT_NEAR(late_input(0.0), gain * 1e-9, 0.01 * gain * 1e-9);
  EXPECT_LT(late_input(1000.0), 1e-3 * gain * 1e-9);  // the Blackman window's -74 dB
}

TEST(PreviewStageInverse, RefusesABandwidthOutsideItsRangeOrTooLongForThePreview) {
  using testing::refused_field;
  const DiscreteLinearStage stage = discretise(LinearStageSpec::sum_of_modes(kTwoModes, 1.5 * kDt), kDt);
  EXPECT_EQ(refused_field([&] { PreviewStageInverse(stage, kPreview, -1.0); }), "reference_bandwidth_hz");
  EXPECT_EQ(refused_field([&] { PreviewStageInverse(stage, kPreview, 5000.0); }), "reference_bandwidth_hz");
  EXPECT_EQ(refused_field([&] { PreviewStageInverse(stage, kPreview, 10.0); }), "reference_bandwidth_hz");
  EXPECT_EQ(refused_field([&] { PreviewStageInverse(stage, kPreview, std::nan("")); }), "reference_bandwidth_hz");
  // 1 tick of delay, 1 outside zero (-4.78), 40 for the low-pass, and the series' taps.
  EXPECT_EQ(refused_field([&] { PreviewStageInverse(stage, 41, 1000.0); }), "preview_ticks");
  EXPECT_NO_THROW(PreviewStageInverse(stage, 100, 1000.0));
}

TEST(PreviewStageInverse, RestsWhereResetHoldsOnANonFiniteReferenceAndStepsWithoutAllocating) {
  const DiscreteLinearStage stage =
      discretise(LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-100.0, 995.0}, {-2000.0, 0.0}}, 1.5 * kDt), kDt);
  PreviewStageInverse inverse(stage, kPreview, 800.0);
  inverse.reset(0.5e-6);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(inverse.step(0.5e-6), 0.5e-6, 1e-18);
  const double before = inverse.last_input();
  EXPECT_EQ(inverse.step(std::nan("")), before);
  EXPECT_NEAR(inverse.step(0.5e-6), 0.5e-6, 1e-18);
  testing::AllocationCounter counter;
  double sum = 0.0;
  for (int k = 0; k < 2000; ++k) sum += inverse.step(1e-9 * std::sin(0.01 * k));
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace hystloop

namespace hystloop {
namespace {
TEST(PreviewStageInverse, SixteenStatesOfModesWithAFractionalDelayReproduceTheReference) {
  // Eight modes from 200 Hz to 4.5 kHz, the most the stage takes, with 2.3 ticks of delay.
  const std::vector<Mode> modes{{200.0, 0.05, 0.3},  {450.0, 0.02, 0.2},   {780.0, 0.03, 0.15},   {1200.0, 0.01, 0.1},
                                {1800.0, 0.02, 0.1}, {2400.0, 0.02, 0.08}, {3300.0, 0.015, 0.04}, {4500.0, 0.01, 0.03}};
  const DiscreteLinearStage undelayed = discretise(LinearStageSpec::sum_of_modes(modes), kDt);
  EXPECT_EQ(undelayed.states(), 16);
  EXPECT_EQ(PreviewStageInverse(undelayed, kPreview).outside_zeros(), 0);
  EXPECT_LT(worst_tracking_error(undelayed, kPreview, 9), 1e-9 * 1.2e-6);
  // The delay's fraction pushes three zeros outside, the closest at |z| = 1.047: 500 ticks are
  // refused, naming what is needed.
  const DiscreteLinearStage delayed = discretise(LinearStageSpec::sum_of_modes(modes, 2.3 * kDt), kDt);
  try {
    PreviewStageInverse inverse(delayed, kPreview);
    FAIL() << "accepted, bound " << inverse.truncation_error_bound();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "preview_ticks");
    EXPECT_NE(std::string(e.what()).find("need about 613 ticks"), std::string::npos) << e.what();
  }
  const PreviewStageInverse inverse(delayed, 700);
  EXPECT_EQ(inverse.outside_zeros(), 3);
  EXPECT_LE(inverse.truncation_error_bound(), PreviewStageInverse::kMaxTruncationError);
  EXPECT_LT(worst_tracking_error(delayed, 700, 9), 1e-9 * 1.2e-6);
}
}  // namespace
}  // namespace hystloop
