// Error bounds under parameter mismatch: Propositions 3.2 and 3.3 (and the paper's numbers).
#include "models/katalenic_bounds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "models/katalenic_operator.hpp"
#include "support/smooth_signal.hpp"

namespace hystloop {
namespace {

// A smooth input with many reversals (tests/support/smooth_signal.hpp): 3-25 cycles, centred on 0.
std::vector<double> smooth_signal(std::mt19937_64& rng, double amplitude, std::size_t n) {
  return testing::smooth_signal(rng, amplitude, 0.0, n, {3.0, 25.0, 0.1});
}

// The paper's Example 1: RH(0.14, 0.1, 8, 5) gives Delta_b <= 0.13, and 0.182 after the output
// shaping 1.4 out; Example 2: RH(0.06, 0.005, 5, 2.5) gives Delta_a <= 0.03.
TEST(KatalenicBounds, ReproducesThePapersNumbers) {
  const KatalenicFamily example1{0.14, 0.1, 8.0, 5.0};
  EXPECT_NEAR(katalenic_compensation_error_bound(example1), 0.13, 0.0005);
  EXPECT_NEAR(katalenic_compensation_error_bound(example1, ShapingFunction::make_linear(1.4)), 0.182, 0.0005);
  EXPECT_NEAR(katalenic_inverse_error_bound(KatalenicFamily{0.06, 0.005, 5.0, 2.5}), 0.03, 0.0005);
}

// The four corners (13) and the extremum point hold the supremum of |(14)| over the whole family
// and all x >= 0: compare with a dense grid.
TEST(KatalenicBounds, CornersHoldTheSupremumOfTheEnvelope) {
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const KatalenicFamily f{0.1 + unit(rng), 0.0, 0.5 + 10.0 * unit(rng), 0.0};
    KatalenicFamily g = f;
    g.dk1 = 0.9 * f.k1 * unit(rng);
    g.dk2 = 0.9 * f.k2 * unit(rng);
    double brute = 0.0;
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) {
        const double k1_bar = g.k1 - g.dk1 + 2.0 * g.dk1 * i / 20.0;
        const double k2_bar = g.k2 - g.dk2 + 2.0 * g.dk2 * j / 20.0;
        for (int m = 0; m <= 2000; ++m) {
          const double x = 10.0 / g.k2 * m / 2000.0;
          brute = std::max(brute, std::abs(katalenic_error_envelope(g.k1, k1_bar, g.k2, k2_bar, x)));
        }
      }
    }
    const double bound = katalenic_inverse_error_bound(g);
    EXPECT_GE(bound, brute * (1 - 1e-12));
    EXPECT_LE(bound, brute * (1 + 1e-4) + 1e-15);
  }
}

struct Mismatch {
  KatalenicFamily family;
  double k1_bar = 0.0, k2_bar = 0.0;
};

Mismatch sample_mismatch(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Mismatch m;
  m.family.k1 = 0.2 + 1.8 * unit(rng);
  m.family.k2 = 0.5 + 9.5 * unit(rng);
  m.family.dk1 = 0.8 * m.family.k1 * unit(rng);
  m.family.dk2 = 0.8 * m.family.k2 * unit(rng);
  // Half of the samples on the family's corners, where the bound is tightest.
  const bool corner = unit(rng) < 0.5;
  auto pick = [&](double centre, double half) {
    return corner ? centre + (unit(rng) < 0.5 ? -half : half) : centre + half * (2.0 * unit(rng) - 1.0);
  };
  m.k1_bar = pick(m.family.k1, m.family.dk1);
  m.k2_bar = pick(m.family.k2, m.family.dk2);
  return m;
}

// Proposition 3.2: two inverse operators, nominal and a member of the family, from the same
// initial state and fed the same u_d with many reversals (minor loops included), never differ by
// more than Delta_a. Proposition 3.3: the plant H(k1*, k2*) fed by the nominal inverse misses
// u_d by at most Delta_b <= Delta_a (to within 1 %, see below).
// KATALENIC_TRIALS=<n> runs more mismatches than the default 400.
TEST(KatalenicBounds, Propositions32And33HoldForSampledMismatches) {
  std::mt19937_64 rng(3233);
#ifdef __SANITIZE_ADDRESS__
  const int trials = 60;
#else
  const int trials = std::getenv("KATALENIC_TRIALS") ? std::atoi(std::getenv("KATALENIC_TRIALS")) : 400;
#endif
  double tightest_a = 0.0, tightest_b = 0.0;
  for (int trial = 0; trial < trials; ++trial) {
    const Mismatch m = sample_mismatch(rng);
    const double bound = katalenic_inverse_error_bound(m.family);
    const double amplitude = (0.5 + 8.0 * std::uniform_real_distribution<double>(0.0, 1.0)(rng)) * m.family.k1;
    const auto ud = smooth_signal(rng, amplitude, 4000);
    const double k1 = m.family.k1, k2 = m.family.k2;

    KatalenicInverseOperator nominal, member;
    KatalenicDirectOperator plant;
    nominal.reset(ud[0], ud[0]);
    member.reset(ud[0], ud[0]);
    plant.reset(ud[0], ud[0]);
    double worst_a = 0.0, worst_b = 0.0;
    for (double u : ud) {
      const double v = nominal.apply(u, k1, k2);
      worst_a = std::max(worst_a, std::abs(member.apply(u, m.k1_bar, m.k2_bar) - v));
      worst_b = std::max(worst_b, std::abs(plant.apply(v, m.k1_bar, m.k2_bar) - u));
    }
    EXPECT_LE(worst_a, bound * (1 + 1e-9) + 1e-12) << "trial " << trial;
    // Prop. 3.3's proof treats H as a static 1-Lipschitz map; with its memory (different latched
    // states for v and v + Delta_a) the bound is exceeded slightly: up to 0.30 % of Delta_a in
    // 9 of 5000 mismatches (KATALENIC_TRIALS=5000), always with k1* = k1 + dk1 and the error near
    // its asymptote |dk1|. Hence the 1 % allowance here; Prop. 3.2 holds to rounding.
    EXPECT_LE(worst_b, bound * 1.01) << "trial " << trial << std::setprecision(17) << " worst " << worst_b << " bound "
                                     << bound << " k1 " << m.family.k1 << " dk1 " << m.family.dk1 << " k2 "
                                     << m.family.k2 << " dk2 " << m.family.dk2 << " k1bar " << m.k1_bar << " k2bar "
                                     << m.k2_bar;
    tightest_a = std::max(tightest_a, worst_a / bound);
    tightest_b = std::max(tightest_b, worst_b / bound);
  }
  std::printf("largest error / bound over %d mismatches: Prop 3.2 %.9f, Prop 3.3 %.9f\n", trials, tightest_a,
              tightest_b);
  EXPECT_GT(tightest_a, 0.5);  // the bound is not vacuous
  EXPECT_LE(tightest_b, 1.01);
}

TEST(KatalenicBounds, FamilyValidationNamesTheField) {
  auto field_of = [](KatalenicFamily f) -> std::string {
    try {
      f.validate();
    } catch (const ParameterError& e) {
      return e.field();
    }
    return "";
  };
  EXPECT_EQ(field_of({0.1, 0.05, 8.0, 2.0}), "");
  EXPECT_EQ(field_of({0.0, 0.0, 8.0, 2.0}), "k1");
  EXPECT_EQ(field_of({0.1, 0.1, 8.0, 2.0}), "dk1");
  EXPECT_EQ(field_of({0.1, -0.01, 8.0, 2.0}), "dk1");
  EXPECT_EQ(field_of({0.1, 0.05, NAN, 2.0}), "k2");
  EXPECT_EQ(field_of({0.1, 0.05, 8.0, 9.0}), "dk2");
  EXPECT_THROW(katalenic_inverse_error_bound(KatalenicFamily{0.1, 0.2, 8.0, 2.0}), ParameterError);
}

TEST(KatalenicBounds, InputDependentK2Deviation) {
  KatalenicParams p;
  EXPECT_EQ(katalenic_k2_deviation(p), 0.0);
  EXPECT_EQ(katalenic_input_dependent_k2_bound(p), 0.0);  // constant k2: the inverse is exact
  p.k2 = 0.03;
  p.k2_slope = 5e-5;
  EXPECT_NEAR(katalenic_k2_deviation(p), 5e-5 * 40.0, 1e-15);  // Prop. 4.3: sup|phi'| k1
  EXPECT_GT(katalenic_input_dependent_k2_bound(p), 0.0);
}

}  // namespace
}  // namespace hystloop
