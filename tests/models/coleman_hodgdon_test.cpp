// Coleman–Hodgdon model of Banning et al. (2001): the closed-form step against an independent
// fine integrator, the paper's Theorems 1 and 3 on simulated stationary loops, validation, and
// seeded properties.

#include "models/coleman_hodgdon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "models/coleman_hodgdon_theory.hpp"
#include "models/loop_features.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kPi = std::numbers::pi;

// Independent reference: classic RK4 on dw/du = -sigma alpha (w - f(u)) + g(u) with n substeps.
// g is discontinuous at +-s_max, so the substeps are aligned to the breakpoints.
double rk4_reference(const ColemanHodgdonParams& p, double u0, double u1, double w0, int n) {
  const double sigma = u1 > u0 ? 1.0 : -1.0;
  auto rhs = [&](double u, double w, double g_side) { return -sigma * p.alpha * (w - p.f(u)) + g_side; };
  std::vector<double> pts{u0};
  for (double br : {-p.s_max, p.s_max}) {
    if ((br - u0) * sigma > 0.0 && (u1 - br) * sigma > 0.0) pts.push_back(br);
  }
  std::sort(pts.begin() + 1, pts.end(), [&](double x, double y) { return (x - y) * sigma < 0.0; });
  pts.push_back(u1);
  double w = w0;
  for (std::size_t j = 0; j + 1 < pts.size(); ++j) {
    const double g_side = p.g(0.5 * (pts[j] + pts[j + 1]));  // g of this piece, also at its ends
    const double h = (pts[j + 1] - pts[j]) / n;
    for (int i = 0; i < n; ++i) {
      const double u = pts[j] + i * h;
      const double k1 = rhs(u, w, g_side);
      const double k2 = rhs(u + 0.5 * h, w + 0.5 * h * k1, g_side);
      const double k3 = rhs(u + 0.5 * h, w + 0.5 * h * k2, g_side);
      const double k4 = rhs(u + h, w + h * k3, g_side);
      w += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
  }
  return w;
}

struct Loop {
  std::vector<double> u;
  std::vector<double> w;
};

// u = offset + A sin(2 pi i / n) until the loop is stationary (turning points converge by
// e^{-4 alpha A} per period, eqs. (12)-(13)); returns the last period.
Loop stationary_loop(const ColemanHodgdonParams& p, double offset, double amplitude, int n) {
  ColemanHodgdon ch(p);
  ch.reset(offset);
  const int periods = 2 + static_cast<int>(std::ceil(30.0 / (4.0 * p.alpha * amplitude)));
  Loop loop;
  for (int k = 0; k < periods; ++k) {
    for (int i = 0; i < n; ++i) {
      const double u = offset + amplitude * std::sin(2.0 * kPi * i / n);
      const double w = ch.step(u);
      if (k == periods - 1) {
        loop.u.push_back(u);
        loop.w.push_back(w);
      }
    }
  }
  return loop;
}

TEST(ColemanHodgdonParams, DefaultsAreTable1InSi) {
  const ColemanHodgdonParams p;
  EXPECT_DOUBLE_EQ(p.a, 8.58e-9);
  EXPECT_DOUBLE_EQ(p.b, 6.07e-9);
  EXPECT_DOUBLE_EQ(p.alpha, 0.0123);
  EXPECT_NO_THROW(p.validate());
}

TEST(ColemanHodgdonParams, FAndGFollowEquations19And20) {
  ColemanHodgdonParams p;
  p.s_max = 100.0;
  EXPECT_DOUBLE_EQ(p.f(50.0), p.a * 50.0);
  EXPECT_DOUBLE_EQ(p.f(150.0), p.a * 100.0);
  EXPECT_DOUBLE_EQ(p.f(-150.0), -p.a * 100.0);
  EXPECT_DOUBLE_EQ(p.g(-100.0), p.b);
  EXPECT_DOUBLE_EQ(p.g(100.5), 0.0);
}

std::string field_of(const ColemanHodgdonParams& p) {
  try {
    p.validate();
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "";
}

TEST(ColemanHodgdonParams, ValidationNamesTheField) {
  ColemanHodgdonParams p;
  p.a = -1.0;
  EXPECT_EQ(field_of(p), "a");
  p = {};
  p.b = 0.0;
  EXPECT_EQ(field_of(p), "b");
  p = {};
  p.b = 1.01 * p.a;  // (4): g <= f' fails
  EXPECT_EQ(field_of(p), "b");
  p = {};
  p.b = 0.49 * p.a;  // (5) fails: branches would not be monotone
  EXPECT_EQ(field_of(p), "b");
  p = {};
  p.alpha = 0.0;
  EXPECT_EQ(field_of(p), "alpha");
  p = {};
  p.s_max = std::nan("");
  EXPECT_EQ(field_of(p), "s_max");
  p = {};
  p.alpha = -1.0;
  EXPECT_THROW(ColemanHodgdon{p}, ParameterError);

  ColemanHodgdon ch;
  EXPECT_THROW(ch.set_params(p), ParameterError);
  EXPECT_DOUBLE_EQ(ch.params().alpha, 0.0123);  // unchanged
  try {
    ch.set_params(p);
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("alpha: must be > 0"), std::string::npos) << e.what();
  }
}

TEST(ColemanHodgdon, ResetStartsOnTheCentreLineOrAtAGivenState) {
  ColemanHodgdon ch;
  ch.reset(40.0);
  EXPECT_DOUBLE_EQ(ch.output(), 8.58e-9 * 40.0);
  EXPECT_DOUBLE_EQ(ch.step(40.0), 8.58e-9 * 40.0);  // no motion, no change
  ch.reset(-10.0, 1e-7);
  EXPECT_DOUBLE_EQ(ch.input(), -10.0);
  EXPECT_DOUBLE_EQ(ch.forward(-10.0), 1e-7);
}

TEST(ColemanHodgdon, NonFiniteInputReturnsNanAndKeepsState) {
  ColemanHodgdon ch;
  ch.step(30.0);
  const double w = ch.output();
  EXPECT_TRUE(std::isnan(ch.step(std::nan(""))));
  EXPECT_TRUE(std::isnan(ch.step(INFINITY)));
  EXPECT_EQ(ch.output(), w);
  EXPECT_EQ(ch.input(), 30.0);
}

// The closed-form step has no truncation error: against RK4 with 20000 substeps per piece
// (itself accurate to ~1e-16 relative here) the difference is rounding, < 1e-12 of the stroke.
TEST(ColemanHodgdon, ClosedFormStepMatchesAFineRk4Reference) {
  ColemanHodgdonParams p;
  p.s_max = 200.0;  // so that some segments cross the saturation breakpoints
  std::mt19937_64 rng(20010515);
  std::uniform_real_distribution<double> target(-300.0, 300.0);
  ColemanHodgdon ch(p);
  double u = 0.0;
  double w = ch.output();
  double worst = 0.0;
  int crossings = 0;
  for (int k = 0; k < 40; ++k) {
    const double u1 = target(rng);
    const double ref = rk4_reference(p, u, u1, w, 20000);
    const double got = ch.step(u1);
    worst = std::max(worst, std::abs(got - ref));
    if (std::abs(u1) > p.s_max || std::abs(u) > p.s_max) ++crossings;
    u = u1;
    w = got;
  }
  const double stroke = p.a * p.s_max;
  std::printf("closed-form CH step vs RK4 (20000 substeps/piece): max |error| = %.3g m = %.3g of a*s_max\n", worst,
              worst / stroke);
  EXPECT_GT(crossings, 5);
  EXPECT_LT(worst, 1e-12 * stroke);
}

// Rate independence and consistency: one big step equals many small steps on the same path.
TEST(ColemanHodgdon, OneStepEqualsManySmallStepsOnAMonotonePath) {
  ColemanHodgdonParams p;
  p.s_max = 100.0;
  ColemanHodgdon coarse(p);
  ColemanHodgdon fine(p);
  coarse.reset(-80.0, -2e-7);
  fine.reset(-80.0, -2e-7);
  for (double target : {150.0, -30.0, 20.0, -140.0}) {
    const double start = fine.input();
    for (int i = 1; i <= 1000; ++i) fine.step(start + (target - start) * i / 1000.0);
    EXPECT_NEAR(coarse.step(target), fine.output(), 1e-13 * p.a * p.s_max) << target;
  }
}

// Theorem 3 for several offsets and amplitudes: the stationary loop's features, extracted from the
// simulated samples by loop_features, against the closed forms (21)-(24).
//  - centre (a u_offset), slope (21), eta (23), area (24) are exact: the only error is the
//    extraction's polynomial fit, < 1e-6 relative;
//  - delta: the paper's (22) is an approximation (1 - e^{-alpha delta/2} ~ alpha delta/2). Against
//    the exact delta (root of the closed-form branch, matched here to 1e-6) it is always high:
//    +0.016 % at A = 5 V, +0.35 % at 25 V, +1.0 % at 50 V, +1.4 % at 100 V, +1.0 % at 150 V,
//    +0.6 % at 200 V; the worst over all amplitudes is +1.42 % at alpha A = 1.10 (A = 90 V, see
//    DeltaClosedFormErrorPeaksNearAlphaAOfOne). The test bounds it by 2 % and prints the table.
TEST(ColemanHodgdon, Theorem3ClosedFormsMatchSimulatedLoops) {
  const ColemanHodgdonParams p;
  struct Case {
    double offset;
    double amplitude;
  };
  const Case cases[] = {{0.0, 5.0}, {0.0, 25.0}, {-40.0, 50.0}, {30.0, 100.0}, {0.0, 150.0}, {-50.0, 200.0}};
  std::printf(
      "  u_off     A   alpha*A | delta sim [V]  exact [V]  (22) [V] (22)/exact-1  small-amp | "
      "slope err  eta err   area err\n");
  for (const Case& c : cases) {
    const Loop loop = stationary_loop(p, c.offset, c.amplitude, 4000);
    const LoopFeatureResult r = extract_loop_features(loop.u, loop.w);
    ASSERT_TRUE(r.ok()) << describe(r.status);
    const LoopFeatures& got = r.features;
    const LoopFeatures exact = exact_loop_features(p, c.offset, c.amplitude);
    const LoopFeatures paper = theorem3_features(p, c.offset, c.amplitude);
    const LoopFeatures small = theorem3_small_amplitude(p, c.offset, c.amplitude);
    const double height = exact.y_right - exact.y_left;
    SCOPED_TRACE(::testing::Message() << "offset " << c.offset << " V, A " << c.amplitude << " V");
    EXPECT_NEAR(got.u_centre, c.offset, 1e-9);
    EXPECT_NEAR(got.y_centre, p.a * c.offset, 1e-7 * height);  // Theorem 3: centre (u, a u)
    EXPECT_NEAR(got.y_left, exact.y_left, 1e-7 * height);
    EXPECT_NEAR(got.y_right, exact.y_right, 1e-7 * height);
    EXPECT_NEAR(got.slope, paper.slope, 1e-6 * paper.slope);
    EXPECT_NEAR(got.eta, paper.eta, 1e-6 * paper.eta);
    EXPECT_NEAR(got.area, paper.area, 1e-6 * paper.area);
    EXPECT_NEAR(got.delta, exact.delta, 1e-6 * exact.delta);
    EXPECT_NEAR(paper.delta, exact.delta, 0.02 * exact.delta);  // (22) is approximate
    EXPECT_GT(paper.delta, exact.delta);
    std::printf("%7.1f %5.0f %8.4f | %12.6g %10.6g %10.6g %+11.3e %10.6g | %+9.1e %+9.1e %+9.1e\n", c.offset,
                c.amplitude, p.alpha * c.amplitude, got.delta, exact.delta, paper.delta,
                paper.delta / exact.delta - 1.0, small.delta, got.slope / paper.slope - 1.0, got.eta / paper.eta - 1.0,
                got.area / paper.area - 1.0);
  }
}

// The paper's (22) against the exact delta over every amplitude up to s_max: always high, by at
// most 1.42 % (at alpha A = 1.10), tending to 0 for alpha A -> 0 and alpha A -> infinity.
TEST(ColemanHodgdon, DeltaClosedFormErrorPeaksNearAlphaAOfOne) {
  const ColemanHodgdonParams p;
  double worst = 0.0;
  double at = 0.0;
  for (double amplitude = 0.5; amplitude <= p.s_max; amplitude *= 1.01) {
    const double rel = ch_horizontal_aperture(p, amplitude) / ch_horizontal_aperture_exact(p, amplitude) - 1.0;
    EXPECT_GT(rel, 0.0) << amplitude;
    if (rel > worst) {
      worst = rel;
      at = amplitude;
    }
  }
  std::printf("(22) vs exact delta: worst %+.4f %% at A = %.1f V (alpha A = %.3f)\n", 100.0 * worst, at, p.alpha * at);
  EXPECT_NEAR(worst, 0.0142, 0.0005);
  EXPECT_NEAR(p.alpha * at, 1.10, 0.05);
}

// The right-hand approximations of Theorem 3 hold for alpha A << 1 (here alpha A = 0.06): the
// slope is b to 0.1 %, the apertures and area to a few percent; at alpha A = 1.2 they do not.
TEST(ColemanHodgdon, Theorem3SmallAmplitudeApproximations) {
  const ColemanHodgdonParams p;
  const LoopFeatures exact = exact_loop_features(p, 0.0, 5.0);
  const LoopFeatures small = theorem3_small_amplitude(p, 0.0, 5.0);
  EXPECT_NEAR(small.slope, exact.slope, 1e-3 * exact.slope);
  EXPECT_NEAR(small.eta, exact.eta, 0.07 * exact.eta);
  EXPECT_NEAR(small.delta, exact.delta, 0.07 * exact.delta);
  EXPECT_NEAR(small.area, exact.area, 0.05 * exact.area);
  const LoopFeatures exact_big = exact_loop_features(p, 0.0, 100.0);
  const LoopFeatures small_big = theorem3_small_amplitude(p, 0.0, 100.0);
  EXPECT_GT(std::abs(small_big.area / exact_big.area - 1.0), 0.2);
  EXPECT_TRUE(std::isnan(theorem3_features(p, 0.0, 800.0).eta));  // beyond s_max
  EXPECT_TRUE(std::isnan(ch_slope(p, 0.0)));
}

// Theorem 1: a loop driven around the origin is centred on the origin. Checked directly on the
// simulated turning points (samples hit u = +-A exactly), not through the extraction.
TEST(ColemanHodgdon, Theorem1LoopAroundZeroIsCentredOnTheOrigin) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    ColemanHodgdonParams p;
    p.a = 5e-9 + 10e-9 * unit(rng);
    p.b = p.a * (0.5 + 0.5 * unit(rng));
    p.alpha = 0.001 + 0.05 * unit(rng);
    const double amplitude = 10.0 + 200.0 * unit(rng);
    const Loop loop = stationary_loop(p, 0.0, amplitude, 400);
    const double w_max = loop.w[100];  // i = n/4: u = +A
    const double w_min = loop.w[300];  // i = 3n/4: u = -A
    EXPECT_NEAR(w_max + w_min, 0.0, 1e-12 * (w_max - w_min)) << "trial " << trial;
    EXPECT_NEAR(w_max, ch_right_turning_point(p, 0.0, amplitude), 1e-12 * (w_max - w_min));
  }
}

// Seeded property: random valid parameters and random inputs (steps, sweeps, beyond +-s_max).
// Outputs are finite and stay within max(|w0|, a s_max + b / alpha), the invariant set of the ODE;
// inside +-s_max with b >= a/2, branches are monotone (inequality (5)): dw has the sign of du.
TEST(ColemanHodgdon, PropertyRandomParamsAndInputsStayFiniteBoundedAndMonotone) {
  std::mt19937_64 rng(0xC0FFEE);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    ColemanHodgdonParams p;
    p.a = 1e-9 * std::pow(10.0, 2.0 * unit(rng));
    p.b = p.a * (0.5 + 0.5 * unit(rng));
    p.alpha = 1e-3 * std::pow(10.0, 2.0 * unit(rng));
    p.s_max = 50.0 + 950.0 * unit(rng);
    ColemanHodgdon ch(p);
    const double bound = p.a * p.s_max + p.b / p.alpha;
    double u = 0.0;
    double w = ch.output();
    for (int i = 0; i < 500; ++i) {
      const bool inside = trial % 2 == 0;
      const double span = inside ? p.s_max : 1.5 * p.s_max;
      const double u1 = (i % 7 == 0) ? span * (2.0 * unit(rng) - 1.0)
                                     : std::clamp(u + 0.05 * span * (2.0 * unit(rng) - 1.0), -span, span);
      const double w1 = ch.step(u1);
      ASSERT_TRUE(std::isfinite(w1));
      ASSERT_LE(std::abs(w1), bound * (1.0 + 1e-12));
      if (inside) {
        ASSERT_GE((w1 - w) * (u1 - u), -1e-15 * bound * span) << trial << " " << i;
      }
      u = u1;
      w = w1;
    }
  }
}

TEST(ColemanHodgdon, StepAllocatesNothing) {
  ColemanHodgdon ch;
  double sink = 0.0;
  hystloop::testing::AllocationCounter counter;
  for (int i = 0; i < 10000; ++i) sink += ch.step(300.0 * std::sin(0.001 * i)) + ch.forward(-0.5 * i);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace hystloop
