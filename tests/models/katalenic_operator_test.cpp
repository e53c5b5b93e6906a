// The bare Katalenic operator pair (operator units): Lambert W at extreme arguments, eqs. (2)/(4),
// Remark 2.3 asymptotes, Lemma 3.1, Prop. 4.1 at extreme k2, derivatives (7)-(8).
#include "models/katalenic_operator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "support/smooth_signal.hpp"

namespace hystloop {
namespace {

// A smooth input with many reversals (tests/support/smooth_signal.hpp), centred on 0.
std::vector<double> smooth_signal(std::uint64_t seed, double amplitude, std::size_t n) {
  return testing::smooth_signal(seed, amplitude, 0.0, n);
}

int reversals(const std::vector<double>& s) {
  int count = 0;
  for (std::size_t k = 2; k < s.size(); ++k) count += ((s[k] - s[k - 1]) * (s[k - 1] - s[k - 2]) < 0.0);
  return count;
}

TEST(LambertW, KnownValuesAndNoThrowAtExtremes) {
  EXPECT_EQ(lambert_w0_nothrow(0.0), 0.0);
  EXPECT_NEAR(lambert_w0_nothrow(std::exp(1.0)), 1.0, 1e-15);
  EXPECT_NEAR(lambert_w0_nothrow(-1.0 / std::exp(1.0)), -1.0, 1e-7);  // branch point
  EXPECT_NEAR(lambert_w0_nothrow(1e-300), 1e-300, 1e-315);
  const double big = std::numeric_limits<double>::max();
  const double w = lambert_w0_nothrow(big);
  EXPECT_NEAR(w + std::log(w), std::log(big), 1e-12 * std::log(big));
}

TEST(LambertW, LogDomainSolvesWPlusLogWEqualsS) {
  for (double s : {690.0, 700.0, 1e3, 1e4, 1e6, 1e12, 1e100, 1e300}) {
    const double w = lambert_w0_of_exp(s);
    EXPECT_NEAR((w + std::log(w)) / s, 1.0, 4e-16) << "s = " << s;
  }
  // Below the threshold it is Boost's lambert_w0 of e^s, including underflow to 0.
  EXPECT_EQ(lambert_w0_of_exp(-800.0), 0.0);
  EXPECT_NEAR(lambert_w0_of_exp(1.0), 1.0, 1e-15);
  EXPECT_NEAR(lambert_w0_of_exp(600.0), lambert_w0_nothrow(std::exp(600.0)), 1e-13);
}

TEST(LambertW, ContinuousAcrossLogDomainThreshold) {
  // dW(e^s)/ds = W / (1 + W): both sides of the switch follow the same curve to rounding.
  const double delta = 1e-6;
  const double below = lambert_w0_of_exp(kLogDomainThreshold - delta);
  const double above = lambert_w0_of_exp(kLogDomainThreshold + delta);
  const double w = lambert_w0_of_exp(kLogDomainThreshold);
  EXPECT_NEAR(above - below, 2.0 * delta * w / (1.0 + w), 1e-12);
  EXPECT_NEAR(
      (lambert_w0_nothrow(std::exp(kLogDomainThreshold + 0.5)) - lambert_w0_of_exp(kLogDomainThreshold + 0.5)) / w, 0.0,
      1e-15);
}

TEST(LambertW, Lemma31Inequalities) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> a_dist(0.0, 50.0), b_dist(-50.0, 50.0);
  for (int i = 0; i < 20000; ++i) {
    const double a = a_dist(rng), b = b_dist(rng);
    const double w = lambert_w0_of_exp(std::log(a) + b);  // W(a e^b)
    if (a < b) {
      EXPECT_LE(a, w * (1 + 1e-14));
      EXPECT_LT(w, b);
    } else if (a > b) {
      EXPECT_LT(b, w);
      EXPECT_LT(w, a);
    }
  }
  for (double a : {0.5, 3.0, 40.0, 800.0}) EXPECT_NEAR(lambert_w0_of_exp(std::log(a) + a), a, 1e-13 * a);  // (11a)
}

TEST(KatalenicBranch, StartsAtZeroAndReachesTheAsymptote) {
  for (double k2 : {0.01, 1.0, 1e3, 1e6}) {
    for (double m_star : {0.0, 0.3, 1.0, 2.0}) {
      EXPECT_NEAR(katalenic_direct_branch(k2, m_star, 0.0), 0.0, 1e-12 * (1.0 + m_star)) << k2 << " " << m_star;
      const double far = 60.0 / k2 + 10.0;
      EXPECT_NEAR(katalenic_direct_branch(k2, m_star, far), far - m_star, 1e-12 * far);
      EXPECT_NEAR(katalenic_inverse_branch(k2, m_star, far), far + m_star, 1e-12 * far);
    }
  }
}

// Interior points of (2) and (4) derived by hand from the paper, where W has a closed form:
//  (a) k2 = 1, M* = 2, v~ = 1 + ln 2: the argument of W in (2) is k2 M* e^{k2 (M* - v~)}
//      = 2 e^{1 - ln 2} = e = 1 e^1, so W = 1 and u~ = v~ - M* + W / k2 = 1 + ln 2 - 2 + 1 = ln 2.
//      (4) at u_d~ = ln 2: v~ = ln 2 + 2 (1 - e^{-ln 2}) = ln 2 + 1, the same point back.
//  (b) k2 = 2, M* = 1, v~ = (1 + ln 2) / 2: argument 2 e^{2 (1 - v~)} = 2 e^{1 - ln 2} = e, W = 1,
//      u~ = v~ - 1 + 1/2 = ln 2 / 2; (4): ln 2 / 2 + (1 - e^{-ln 2}) = (1 + ln 2) / 2.
//  (c) k2 = 1/2, M* = 2, v~ = 2: argument 1 e^0 = 1, W(1) = Omega = 0.5671432904097838 (the omega
//      constant, Omega e^Omega = 1), u~ = 2 - 2 + 2 Omega; (4): 2 Omega + 2 (1 - e^{-Omega})
//      = 2 Omega + 2 - 2 Omega = 2, since e^{-Omega} = Omega.
TEST(KatalenicBranch, InteriorPointsDerivedByHand) {
  const double ln2 = std::log(2.0), omega = 0.5671432904097838;
  EXPECT_NEAR(katalenic_direct_branch(1.0, 2.0, 1.0 + ln2), ln2, 1e-15);
  EXPECT_NEAR(katalenic_inverse_branch(1.0, 2.0, ln2), 1.0 + ln2, 1e-15);
  EXPECT_NEAR(katalenic_direct_branch(2.0, 1.0, 0.5 * (1.0 + ln2)), 0.5 * ln2, 1e-15);
  EXPECT_NEAR(katalenic_inverse_branch(2.0, 1.0, 0.5 * ln2), 0.5 * (1.0 + ln2), 1e-15);
  EXPECT_NEAR(katalenic_direct_branch(0.5, 2.0, 2.0), 2.0 * omega, 1e-15);
  EXPECT_NEAR(katalenic_inverse_branch(0.5, 2.0, 2.0 * omega), 2.0, 1e-15);
}

// The same point (a) through the operators, with Definition 2.1's T and M: the direct operator
// started at (v0, u0) = (0, 1), ascending, has M = u0 - v0 = 1 and M* = M + k1 = 2 (k1 = 1); at
// v = 1 + ln 2 (v~ = 1 + ln 2) it gives u = u0 + u~ = 1 + ln 2. Descending from (0, -1) by symmetry
// u = -(1 + ln 2). The inverse started at (u_d0, v0) = (0, -1), ascending, has M = v0 - u_d0 = -1
// and M* = -M + k1 = 2; at u_d = ln 2 it gives v = v0 + v~ = -1 + 1 + ln 2 = ln 2.
TEST(KatalenicOperatorPair, InteriorPointDerivedByHand) {
  const double ln2 = std::log(2.0);
  KatalenicDirectOperator up, down;
  up.reset(0.0, 1.0, 1.0);
  EXPECT_NEAR(up.apply(1.0 + ln2, 1.0, 1.0), 1.0 + ln2, 1e-15);
  down.reset(0.0, -1.0, -1.0);
  EXPECT_NEAR(down.apply(-(1.0 + ln2), 1.0, 1.0), -(1.0 + ln2), 1e-15);
  KatalenicInverseOperator inv;
  inv.reset(0.0, -1.0, 1.0);
  EXPECT_NEAR(inv.apply(ln2, 1.0, 1.0), ln2, 1e-15);
}

TEST(KatalenicBranch, DirectAndInverseBranchesAreInverse) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const double k2 = std::pow(10.0, -2.0 + 8.0 * unit(rng));  // 0.01 .. 1e6, log domain included
    const double m_star = 2.0 * unit(rng);
    const double v_tilde = (5.0 / k2) * unit(rng) + m_star * unit(rng);
    const double u_tilde = katalenic_direct_branch(k2, m_star, v_tilde);
    EXPECT_GE(u_tilde, -1e-12);
    EXPECT_LE(u_tilde, v_tilde + 1e-12);
    // (4) after (2) multiplies the rounding of u~ by the slope 1 + k2 M* e^{-k2 u~} of (4), up
    // to 1 + 2 k1 k2 (2e6 here): the tolerance carries that condition number. (2) after (4) is
    // well conditioned (slope <= 1).
    const double slope = 1.0 + k2 * m_star * std::exp(-k2 * u_tilde);
    EXPECT_NEAR(katalenic_inverse_branch(k2, m_star, u_tilde), v_tilde, 1e-15 * slope * (1.0 + v_tilde + m_star))
        << "k2 " << k2;
    EXPECT_NEAR(katalenic_direct_branch(k2, m_star, katalenic_inverse_branch(k2, m_star, v_tilde)), v_tilde,
                1e-15 * (1.0 + v_tilde + m_star))
        << "k2 " << k2;
  }
}

// Remark 2.3 and the band: ascending the output tends to v - k1, descending to v + k1, and it
// never leaves |u - v| <= k1; the slope du/dv stays in [0, 1] (proof of Prop. 3.3).
TEST(KatalenicDirectOperator, AsymptotesBandAndSlope) {
  const double k1 = 0.5, k2 = 4.0;
  KatalenicDirectOperator op;
  op.reset(0.0, 0.0);
  double last_v = 0.0, last_u = 0.0;
  for (int k = 1; k <= 4000; ++k) {
    const double v = 10.0 * std::sin(6.283185307179586 * k / 2000.0);
    const double u = op.apply(v, k1, k2);
    EXPECT_LE(std::abs(u - v), k1 * (1 + 1e-12));
    const double dv = v - last_v, du = u - last_u;
    EXPECT_GE(du * dv, 0.0);
    EXPECT_LE(std::abs(du), std::abs(dv) * (1 + 1e-9) + 1e-14);
    if (k == 500) {
      EXPECT_NEAR(u, v - k1, 1e-12);  // top of the ascent
    }
    if (k == 1500) {
      EXPECT_NEAR(u, v + k1, 1e-12);  // bottom of the descent
    }
    last_v = v;
    last_u = u;
  }
}

TEST(KatalenicDirectOperator, LatchesThePreviousSampleAtAReversal) {
  KatalenicDirectOperator op;
  op.reset(0.0, 0.0);
  op.apply(1.0, 0.2, 3.0);
  const double u_peak = op.apply(2.0, 0.2, 3.0);
  op.apply(1.5, 0.2, 3.0);  // reversal: (alpha0, beta0) = (2, u(2))
  EXPECT_EQ(op.memory().alpha0(), 2.0);
  EXPECT_EQ(op.memory().beta0(), u_peak);
  EXPECT_EQ(op.memory().direction(), -1.0);
  op.apply(1.5, 0.2, 3.0);  // a hold keeps the branch
  EXPECT_EQ(op.memory().alpha0(), 2.0);
  EXPECT_EQ(op.memory().direction(), -1.0);
}

// Prop. 4.1 at the extremes: k2 from piezo-soft to backlash-hard (log-domain W) in both orders.
TEST(KatalenicOperatorPair, ExactInverseFromSoftToBacklashHard) {
  const auto v = smooth_signal(7, 5.0, 20000);
  ASSERT_GT(reversals(v), 40);
  for (double k2 : {0.05, 3.0, 400.0, 1e4, 1e6}) {
    const double k1 = 1.0;
    KatalenicDirectOperator direct;
    KatalenicInverseOperator inverse;
    direct.reset(v[0], v[0] + 0.3);
    inverse.reset(v[0] + 0.3, v[0]);
    double worst_left = 0.0;
    for (double x : v) worst_left = std::max(worst_left, std::abs(inverse.apply(direct.apply(x, k1, k2), k1, k2) - x));
    // Left: rounding of H times the slope of H^{-1} (<= 1 + 2 k1 k2). Right: well conditioned.
    EXPECT_LT(worst_left, 1e-14 * (1.0 + 2.0 * k1 * k2)) << "left inverse, k2 = " << k2;

    direct.reset(v[0] - 0.3, v[0]);
    inverse.reset(v[0], v[0] - 0.3);
    double worst_right = 0.0;
    for (double z : v)
      worst_right = std::max(worst_right, std::abs(direct.apply(inverse.apply(z, k1, k2), k1, k2) - z));
    EXPECT_LT(worst_right, 1e-13) << "right inverse, k2 = " << k2;
    std::printf("k2 = %g: worst left %.3g, right %.3g (operator units, range 10)\n", k2, worst_left, worst_right);
  }
}

// Proposition 2.7: eqs. (7)-(8) against central differences of the inverse operator along a
// smooth input, on ascending and descending stretches (the second term of (8) changes sign).
TEST(KatalenicInverseOperator, DerivativesMatchFiniteDifferences) {
  const double k1 = 0.4, k2 = 3.0, h = 1e-4;
  auto ud = [](double t) { return 2.0 * std::sin(1.3 * t) + 0.5 * std::sin(3.1 * t); };
  auto ud_dot = [](double t) { return 2.6 * std::cos(1.3 * t) + 1.55 * std::cos(3.1 * t); };
  auto ud_ddot = [](double t) { return -3.38 * std::sin(1.3 * t) - 4.805 * std::sin(3.1 * t); };
  KatalenicInverseOperator op;
  op.reset(ud(0.0), ud(0.0));
  KatalenicInverseOperator probe;
  int ascending = 0, descending = 0;
  double v_previous = ud(0.0);
  for (int k = 1; k < 60000; ++k) {
    const double t = k * h;
    const OperatorRates r = op.apply_with_rates(ud(t), ud_dot(t), ud_ddot(t), k1, k2);
    const double v_before = v_previous;
    v_previous = r.value;
    if (k % 500 != 0 || std::abs(ud_dot(t)) < 0.3) continue;  // away from reversals (v'' jumps there)
    // Central differences: the next sample from a copy of the state (same branch).
    probe = op;
    const double v_next = probe.apply(ud(t + h), k1, k2);
    const double fd_rate = (v_next - v_before) / (2.0 * h);
    const double fd_acc = (v_next - 2.0 * r.value + v_before) / (h * h);
    EXPECT_NEAR(r.rate, fd_rate, 1e-7 * (1.0 + std::abs(r.rate))) << "t = " << t;
    EXPECT_NEAR(r.acceleration, fd_acc, 1e-4 * (1.0 + std::abs(r.acceleration))) << "t = " << t;
    (ud_dot(t) > 0 ? ascending : descending)++;
  }
  EXPECT_GT(ascending, 10);
  EXPECT_GT(descending, 10);
}

}  // namespace
}  // namespace hystloop
