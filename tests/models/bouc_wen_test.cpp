// Bouc–Wen model: the n = 1 closed form against the solution derived here independently, RK4
// (n != 1) against the n = 2 closed form and its order, rate independence, the stationary loop
// (closed, centred, the defaults' stated width), the BIBO bound of Ikhouane et al. (2007),
// validation, and no allocation per step.

#include "models/bouc_wen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

// n = 1, input increasing from (u0, h0), derived from dh/du = alpha d - beta |h| ... with du > 0:
//   h >= 0:  dh/du = alpha d - (beta + gamma) h  ->  h(u) = (ad/l1)(1 - e^{-l1 (u-u0)}) + h0 e^{-l1 (u-u0)}
//   h <  0:  dh/du = alpha d - (beta - gamma) h  ->  the same with l2 = beta - gamma (h0 + ad (u-u0) if
//            l2 = 0), until h = 0 at u* = u0 + ln(1 - l2 h0 / ad) / l2; from (u*, 0) the first case.
double increasing_reference(const BoucWenParams& p, double u0, double h0, double u) {
  const double ad = p.alpha * p.d;
  const double l1 = p.beta + p.gamma;
  const double l2 = p.beta - p.gamma;
  auto relax = [&](double l, double from, double h_from, double to) {
    if (l == 0.0) return h_from + ad * (to - from);
    return (ad / l) * (1.0 - std::exp(-l * (to - from))) + h_from * std::exp(-l * (to - from));
  };
  if (h0 < 0.0) {
    const double u_star = u0 + (l2 == 0.0 ? -h0 / ad : std::log(1.0 - l2 * h0 / ad) / l2);
    if (u <= u_star) return relax(l2, u0, h0, u);
    return relax(l1, u_star, 0.0, u);
  }
  return relax(l1, u0, h0, u);
}

// Decreasing input: the ODE is odd under (u, h) -> (-u, -h), so h(u) = -increasing(-u0, -h0, -u).
double reference(const BoucWenParams& p, double u0, double h0, double u) {
  return u >= u0 ? increasing_reference(p, u0, h0, u) : -increasing_reference(p, -u0, -h0, -u);
}

struct Loop {
  std::vector<double> u;
  std::vector<double> y;
};

// u = A sin(2 pi i / n) from the demagnetised state for `periods` periods; returns every period.
std::vector<Loop> sine_periods(const BoucWenParams& p, double amplitude, int n, int periods) {
  BoucWen bw(p);
  std::vector<Loop> out(periods);
  for (int k = 0; k < periods; ++k) {
    for (int i = 0; i < n; ++i) {
      const double u = amplitude * std::sin(2.0 * kPi * i / n);
      out[k].u.push_back(u);
      out[k].y.push_back(bw.step(u));
    }
  }
  return out;
}

TEST(BoucWenParams, DefaultsAreValidAndBoundIsAlphaDOverBetaPlusGamma) {
  const BoucWenParams p;
  EXPECT_NO_THROW(p.validate());
  EXPECT_EQ(p.n, 1.0);
  EXPECT_DOUBLE_EQ(p.h_bound(), 0.3 * 6.3e-8 / 0.02);
  BoucWenParams q;
  q.n = 2.0;
  q.beta = 2.0e4;
  q.gamma = 1.0e4;
  EXPECT_DOUBLE_EQ(q.h_bound(), std::sqrt(0.3 * 6.3e-8 / 3.0e4));
}

TEST(BoucWenParams, ValidationNamesTheField) {
  using hystloop::testing::refused_field;
  auto field = [](auto mutate) {
    BoucWenParams p;
    mutate(p);
    return refused_field([&] { p.validate(); });
  };
  EXPECT_EQ(field([](BoucWenParams& p) { p.d = 0.0; }), "d");
  EXPECT_EQ(field([](BoucWenParams& p) { p.d = std::nan(""); }), "d");
  EXPECT_EQ(field([](BoucWenParams& p) { p.alpha = -0.1; }), "alpha");
  EXPECT_EQ(field([](BoucWenParams& p) { p.beta = 0.0; }), "beta");
  EXPECT_EQ(field([](BoucWenParams& p) { p.gamma = 1.01 * p.beta; }), "gamma");  // beta - gamma < 0
  EXPECT_EQ(field([](BoucWenParams& p) { p.gamma = -p.beta; }), "gamma");        // beta + gamma = 0
  EXPECT_EQ(field([](BoucWenParams& p) { p.gamma = kInf; }), "gamma");
  EXPECT_EQ(field([](BoucWenParams& p) { p.n = 0.99; }), "n");
  EXPECT_EQ(field([](BoucWenParams& p) { p.n = std::nan(""); }), "n");
  EXPECT_EQ(field([](BoucWenParams& p) { p.rk4_substeps = 0; }), "rk4_substeps");
  EXPECT_EQ(field([](BoucWenParams& p) { p.rk4_substeps = 5000; }), "rk4_substeps");
  // The edges of the class are accepted.
  BoucWenParams edge;
  edge.gamma = edge.beta;  // beta - gamma = 0
  EXPECT_NO_THROW(edge.validate());
  edge.gamma = -0.999 * edge.beta;
  EXPECT_NO_THROW(edge.validate());

  BoucWenParams bad;
  bad.gamma = 2.0 * bad.beta;
  EXPECT_THROW(BoucWen{bad}, ParameterError);
  BoucWen bw;
  EXPECT_THROW(bw.set_params(bad), ParameterError);
  EXPECT_DOUBLE_EQ(bw.params().gamma, 0.005);  // unchanged
  try {
    bw.set_params(bad);
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("gamma: must satisfy -beta < gamma <= beta"), std::string::npos) << e.what();
  }
}

TEST(BoucWen, ResetStartsDemagnetisedOrAtAGivenState) {
  BoucWen bw;
  bw.reset(40.0);
  EXPECT_DOUBLE_EQ(bw.output(), 6.3e-8 * 40.0);
  EXPECT_EQ(bw.hysteretic_state(), 0.0);
  EXPECT_DOUBLE_EQ(bw.step(40.0), 6.3e-8 * 40.0);  // no motion, no change
  bw.reset(-10.0, 2e-7);
  EXPECT_EQ(bw.input(), -10.0);
  EXPECT_DOUBLE_EQ(bw.forward(-10.0), -6.3e-7 - 2e-7);
}

TEST(BoucWen, NonFiniteInputReturnsNanAndKeepsState) {
  for (double n : {1.0, 2.0}) {
    BoucWenParams p;
    p.n = n;
    BoucWen bw(p);
    bw.step(30.0);
    const double y = bw.output();
    const double h = bw.hysteretic_state();
    EXPECT_TRUE(std::isnan(bw.step(std::nan(""))));
    EXPECT_TRUE(std::isnan(bw.step(-kInf)));
    EXPECT_EQ(bw.output(), y);
    EXPECT_EQ(bw.hysteretic_state(), h);
    EXPECT_EQ(bw.input(), 30.0);
  }
}

// n = 1: one step from any (u0, h0) to any u is the closed form above, on both sides of h = 0,
// across the crossing, in both directions, for gamma > 0, gamma < 0 and gamma = beta (l2 = 0).
TEST(BoucWen, N1StepIsTheClosedFormSolution) {
  std::mt19937_64 rng(1995);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  BoucWenParams variants[3];
  variants[1].gamma = -0.8 * variants[1].beta;
  variants[2].gamma = variants[2].beta;
  for (const BoucWenParams& p : variants) {
    BoucWen bw(p);
    const double scale = p.h_bound();
    double worst = 0.0;
    int crossings = 0;
    for (int k = 0; k < 2000; ++k) {
      const double u0 = 200.0 * (2.0 * unit(rng) - 1.0);
      const double h0 = 1.5 * scale * (2.0 * unit(rng) - 1.0);
      const double u1 = u0 + 150.0 * (2.0 * unit(rng) - 1.0);
      bw.reset(u0, h0);
      const double got = bw.step(u1);
      const double h_ref = reference(p, u0, h0, u1);
      worst = std::max(worst, std::abs(bw.hysteretic_state() - h_ref) / scale);
      EXPECT_DOUBLE_EQ(got, p.d * u1 - bw.hysteretic_state());
      if (h0 * h_ref < 0.0) ++crossings;
    }
    std::printf("n = 1 step vs closed form (gamma/beta %+.2f): max |error| = %.3g of h_bound, %d crossings\n",
                p.gamma / p.beta, worst, crossings);
    EXPECT_GT(crossings, 100);
    EXPECT_LT(worst, 1e-12);
  }
}

// One big step equals many small steps on the same monotone path (n = 1: to rounding).
TEST(BoucWen, N1OneStepEqualsManySmallStepsOnAMonotonePath) {
  BoucWen coarse;
  BoucWen fine;
  coarse.reset(-80.0, -9e-7);
  fine.reset(-80.0, -9e-7);
  for (double target : {150.0, -30.0, 20.0, -140.0, -139.0, 100.0}) {
    const double start = fine.input();
    for (int i = 1; i <= 1000; ++i) fine.step(start + (target - start) * i / 1000.0);
    EXPECT_NEAR(coarse.step(target), fine.output(), 1e-12 * BoucWenParams{}.h_bound()) << target;
  }
}

// n = 2 has a closed form too, with s = sign(du) h and p the distance travelled:
//   s >= 0: ds/dp = ad - l1 s^2  ->  s = k tanh(sqrt(ad l1) p + atanh(s0 / k)),  k = sqrt(ad / l1), s0 < k
//   s <  0: ds/dp = ad + l2 s^2  ->  s = sqrt(ad / l2) tan(sqrt(ad l2) p + atan(s0 sqrt(l2 / ad)))
// RK4 matches it, and its error falls as the 4th power of the sub-step (16x per halving).
TEST(BoucWen, Rk4MatchesTheN2ClosedFormWithFourthOrderConvergence) {
  BoucWenParams p;
  p.n = 2.0;
  p.beta = 1.5e4;  // [1/(V m)]: h_bound = sqrt(alpha d / (beta + gamma)) = 0.97 um
  p.gamma = 0.5e4;
  const double ad = p.alpha * p.d;
  const double l1 = p.beta + p.gamma;
  const double l2 = p.beta - p.gamma;
  const double k = std::sqrt(ad / l1);
  struct Case {
    double h0;
    double du;  // increasing input from u = 0, the first case above if h0 >= 0 else the second
  };
  // The negative-side case stays on its side: it reaches 0 at p = atan(|s0| sqrt(l2/ad)) / sqrt(ad l2).
  const Case cases[] = {{0.0, 20.0}, {0.5 * k, 10.0}, {1.3 * k, 10.0}, {-0.8 * k, 4.0}};
  for (const Case& c : cases) {
    double exact;
    if (c.h0 >= 0.0) {
      const double arg = std::sqrt(ad * l1) * c.du;
      exact = c.h0 < k ? k * std::tanh(arg + std::atanh(c.h0 / k)) : k / std::tanh(arg + std::atanh(k / c.h0));
    } else {
      const double arg = std::sqrt(ad * l2) * c.du + std::atan(c.h0 * std::sqrt(l2 / ad));
      ASSERT_LT(arg, 0.0);  // still on the negative side
      exact = std::sqrt(ad / l2) * std::tan(arg);
    }
    double errors[3];
    const int substeps[3] = {4, 8, 16};
    for (int j = 0; j < 3; ++j) {
      p.rk4_substeps = substeps[j];
      BoucWen bw(p);
      bw.reset(0.0, c.h0);
      bw.step(c.du);
      errors[j] = std::abs(bw.hysteretic_state() - exact);
    }
    SCOPED_TRACE(::testing::Message() << "h0 " << c.h0 / k << " k, du " << c.du << " V");
    std::printf(
        "RK4 vs n = 2 closed form, h0 = %+.1f k, du = %4.1f V: error %.3g, %.3g, %.3g of k (4, 8, 16 substeps)\n",
        c.h0 / k, c.du, errors[0] / k, errors[1] / k, errors[2] / k);
    EXPECT_LT(errors[2], 1e-8 * k);
    EXPECT_GT(errors[0] / errors[1], 10.0);  // 16 for a 4th-order method (>= 8 would be 3rd order)
    EXPECT_LT(errors[0] / errors[1], 24.0);
  }
}

// The same sine path sampled at two rates (the fast one hits every sample of the slow one) gives
// the same y at the shared samples: to rounding for n = 1, to RK4's truncation for n = 2.
TEST(BoucWen, RateIndependentAtSharedSamples) {
  BoucWenParams p2;
  p2.n = 2.0;
  p2.beta = 1.5e4;
  p2.gamma = 0.5e4;
  struct Case {
    BoucWenParams params;
    double tolerance;  // of the stroke
  };
  for (const Case& c : {Case{BoucWenParams{}, 1e-12}, Case{p2, 1e-9}}) {
    const int n = 200;
    const int ratio = 7;
    const std::vector<Loop> slow = sine_periods(c.params, 100.0, n, 3);
    const std::vector<Loop> fast = sine_periods(c.params, 100.0, n * ratio, 3);
    double worst = 0.0;
    double stroke = 0.0;
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < n; ++i) {
        worst = std::max(worst, std::abs(slow[k].y[i] - fast[k].y[static_cast<std::size_t>(i) * ratio]));
        stroke = std::max(stroke, std::abs(slow[k].y[i]));
      }
    }
    stroke *= 2.0;
    std::printf("n = %.0f: %d vs %d samples/period, max |y difference| = %.3g of the stroke\n", c.params.n, n,
                n * ratio, worst / stroke);
    EXPECT_LT(worst, c.tolerance * stroke) << "n = " << c.params.n;
  }
}

// A symmetric periodic input: the turning points converge after the first cycle (each cycle closer
// to the last than the one before), the loop then closes to rounding and is centred on the origin
// (the ODE is odd in (u, h)). The defaults' stated shape: stroke 10.8 um for +-100 V, opening at
// u = 0 12.3 % of it, slope of y right after a reversal 0.56 d.
TEST(BoucWen, SymmetricPeriodicInputGivesAClosedCentredLoop) {
  for (double n : {1.0, 2.0}) {
    BoucWenParams p;
    if (n == 2.0) {
      p.n = 2.0;
      p.beta = 1.5e4;
      p.gamma = 0.5e4;
    }
    const int samples = 400;  // u = +A at i = 100, -A at i = 300, 0 at i = 0 (rising) and 200 (falling)
    const std::vector<Loop> loops = sine_periods(p, 100.0, samples, 15);
    const double stroke = loops.back().y[100] - loops.back().y[300];
    double previous_change = kInf;
    for (std::size_t k = 1; k < loops.size(); ++k) {
      const double change =
          std::max(std::abs(loops[k].y[100] - loops[k - 1].y[100]), std::abs(loops[k].y[300] - loops[k - 1].y[300]));
      if (change > 1e-14 * stroke) {
        EXPECT_LT(change, previous_change) << "n " << n << " cycle " << k;
      }
      previous_change = change;
    }
    const Loop& last = loops.back();
    const Loop& before = loops[loops.size() - 2];
    SCOPED_TRACE(::testing::Message() << "n = " << n);
    for (int i = 0; i < samples; ++i) EXPECT_NEAR(last.y[i], before.y[i], 1e-12 * stroke) << i;  // closed
    EXPECT_NEAR(last.y[100] + last.y[300], 0.0, 1e-12 * stroke);                                 // centred
    EXPECT_NEAR(last.y[0] + last.y[200], 0.0, 1e-12 * stroke);
    const double opening = last.y[200] - last.y[0];  // counter-clockwise: falling branch above
    EXPECT_GT(opening, 0.0);
    if (n == 1.0) {
      std::printf("defaults, +-100 V: stroke %.4g m, opening at u = 0 %.4f of it\n", stroke, opening / stroke);
      EXPECT_NEAR(stroke, 10.8e-6, 0.05e-6);
      EXPECT_NEAR(opening / stroke, 0.123, 0.003);
      // Right after the reversal at +A: dy/du = d - dh/du = d (1 - alpha) - (beta - gamma) |h|.
      BoucWen bw(p);
      bw.reset(100.0, 100.0 * p.d - last.y[100]);
      const double slope = (bw.step(99.999) - last.y[100]) / -0.001;
      EXPECT_NEAR(slope / p.d, 0.56, 0.01);
      EXPECT_NEAR(slope, p.d * (1.0 - p.alpha) - (p.beta - p.gamma) * bw.hysteretic_state(), 1e-5 * p.d);
    }
  }
}

// For n = 1 the shape depends on alpha, beta A, gamma A; d only scales it. The header's rescaling
// to the project's +-250 V: 3.17 um of stroke (MemParams::paper_like()'s), the same 12.3 % opening.
TEST(BoucWen, N1LoopShapeScalesWithBetaATimesAndD) {
  BoucWenParams p;
  p.d = 7.4e-9;
  p.beta = 0.006;
  p.gamma = 0.002;
  const std::vector<Loop> scaled = sine_periods(p, 250.0, 400, 15);
  const std::vector<Loop> defaults = sine_periods(BoucWenParams{}, 100.0, 400, 15);
  const double stroke = scaled.back().y[100] - scaled.back().y[300];
  EXPECT_NEAR(stroke, 3.17e-6, 0.01e-6);
  const double stroke0 = defaults.back().y[100] - defaults.back().y[300];
  for (int i = 0; i < 400; ++i) {
    EXPECT_NEAR(scaled.back().y[i] / stroke, defaults.back().y[i] / stroke0, 1e-12) << i;
  }
}

// Class I of Ikhouane, Mañosa & Rodellar (2007): |h| <= max(|h(0)|, (alpha d / (beta + gamma))^(1/n))
// for every input. Random parameters of the class (gamma of both signs, gamma = beta, n from 1 to 4),
// random initial states inside and outside the bound, random walks and jumps. The bound is tight:
// a long monotone sweep from h = 0 ends within 1e-6 of it.
TEST(BoucWen, PropertyStateStaysWithinTheBiboBound) {
  std::mt19937_64 rng(2007);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    BoucWenParams p;
    p.d = 1e-9 * std::pow(10.0, 2.0 * unit(rng));
    p.alpha = 0.05 + 0.9 * unit(rng);
    const double ns[] = {1.0, 1.0, 1.5, 2.0, 3.0, 4.0};
    p.n = ns[trial % 6];
    // A loop a few tens of volts wide whatever n: choose h_bound, then beta + gamma from it.
    const double h_bound = p.alpha * p.d * (10.0 + 40.0 * unit(rng));
    const double sum = p.alpha * p.d / std::pow(h_bound, p.n);
    const double ratio = trial % 10 == 0 ? 1.0 : -0.99 + 1.99 * unit(rng);  // gamma / beta in (-1, 1]
    p.beta = sum / (1.0 + ratio);
    p.gamma = ratio * p.beta;
    p.rk4_substeps = 32;
    ASSERT_NO_THROW(p.validate()) << trial;
    ASSERT_NEAR(p.h_bound(), h_bound, 1e-9 * h_bound);
    BoucWen bw(p);
    const double h0 = (trial % 3 == 0 ? 2.0 : 0.9) * h_bound * (2.0 * unit(rng) - 1.0);
    bw.reset(0.0, h0);
    const double bound = std::max(std::abs(h0), h_bound) * (1.0 + (p.n == 1.0 ? 1e-12 : 1e-9));
    double u = 0.0;
    for (int i = 0; i < 400; ++i) {
      // Jumps only in closed form: RK4 needs sub-steps well inside its stability limit (header).
      const double u1 = (i % 9 == 0 && p.n == 1.0) ? 200.0 * (2.0 * unit(rng) - 1.0)
                                                   : std::clamp(u + 20.0 * (2.0 * unit(rng) - 1.0), -200.0, 200.0);
      ASSERT_TRUE(std::isfinite(bw.step(u1)));
      ASSERT_LE(std::abs(bw.hysteretic_state()), bound) << "trial " << trial << " sample " << i << " n " << p.n;
      u = u1;
    }
    bw.reset(0.0, 0.0);
    for (int i = 1; i <= 250; ++i) bw.step(4.0 * i);  // 1000 V of travel, >= 20 bound widths
    EXPECT_NEAR(bw.hysteretic_state(), h_bound, 1e-6 * h_bound) << "trial " << trial << " n " << p.n;
  }
}

TEST(BoucWen, StepAllocatesNothing) {
  BoucWenParams p2;
  p2.n = 2.0;
  p2.beta = 1.5e4;
  p2.gamma = 0.5e4;
  BoucWen exact;
  BoucWen rk4(p2);
  double sink = 0.0;
  hystloop::testing::AllocationCounter counter;
  for (int i = 0; i < 10000; ++i) {
    const double u = 100.0 * std::sin(0.001 * i);
    sink += exact.step(u) + exact.forward(-u) + rk4.step(u);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace hystloop
