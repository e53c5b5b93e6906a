// Prandtl–Ishlinskii baseline: play operator basics, the exact inverse PI operator (inverse of
// forward and forward of inverse are the identity to rounding over random inputs with many
// reversals, the inverse of the inverse is the forward), validation, the MEM-matched parameter set,
// the bumpless swap and allocation-free per-sample calls.

#include "models/prandtl_ishlinskii.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "core/errors.hpp"
#include "models/mem.hpp"
#include "models/model_concepts.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

static_assert(HysteresisForward<PiModel>);
static_assert(HysteresisInverse<PiInverse>);

#if defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kLong = 50'000;
#else
constexpr std::size_t kLong = 500'000;
#endif

PiParams single_play(double w0, double r1, double w1) {
  PiParams p;
  p.count = 2;
  p.thresholds = {0.0, r1};
  p.weights = {w0, w1};
  return p;
}

// Random valid parameters: count operators, random threshold gaps, weights of either sign
// with every cumulative weight > 0.
PiParams random_params(std::mt19937_64& rng, std::size_t count) {
  std::uniform_real_distribution<double> gap(2.0, 40.0), w(-0.4e-9, 1.5e-9);
  PiParams p;
  p.count = count;
  p.weights[0] = std::uniform_real_distribution<double>(2e-9, 8e-9)(rng);
  double cumulative = p.weights[0];
  for (std::size_t i = 1; i < count; ++i) {
    p.thresholds[i] = p.thresholds[i - 1] + gap(rng);
    p.weights[i] = std::max(w(rng), -0.5 * cumulative);
    cumulative += p.weights[i];
  }
  return p;
}

// Random input with many reversals: a random walk of random-length monotone runs and holds.
class RandomRuns {
 public:
  RandomRuns(std::uint64_t seed, double amplitude) : rng_(seed), a_(amplitude) {}
  double next() {
    if (left_ == 0) {
      left_ = std::uniform_int_distribution<int>(1, 60)(rng_);
      step_ = std::uniform_real_distribution<double>(-1.0, 1.0)(rng_) * a_ / 40.0;
      if (std::uniform_int_distribution<int>(0, 5)(rng_) == 0) step_ = 0.0;  // a hold
    }
    --left_;
    x_ = std::clamp(x_ + step_, -a_, a_);
    return x_;
  }

 private:
  std::mt19937_64 rng_;
  double a_, x_ = 0.0, step_ = 0.0;
  int left_ = 0;
};

TEST(PlayOperator, BandAndFollowing) {
  PiModel m(single_play(1e-9, 10.0, 2e-9));  // y = 1e-9 u + 2e-9 play_10[u]
  auto play = [&] { return (m.output() - 1e-9 * m.input()) / 2e-9; };
  m.reset(0.0);
  EXPECT_EQ(play(), 0.0);
  m.forward(5.0);
  EXPECT_NEAR(play(), 0.0, 1e-12);  // inside the band: holds
  m.forward(25.0);
  EXPECT_NEAR(play(), 15.0, 1e-12);  // pushed: follows u - r
  m.forward(20.0);
  EXPECT_NEAR(play(), 15.0, 1e-12);  // reversal: holds across the 2r band
  m.forward(4.0);
  EXPECT_NEAR(play(), 14.0, 1e-12);  // then follows u + r
  m.reset(30.0);
  EXPECT_NEAR(play(), 20.0, 1e-12);  // reset: demagnetised at 0, loaded to 30
}

TEST(PiModel, SingleOperatorIsLinear) {
  PiParams p;
  p.count = 1;
  p.weights[0] = 3e-9;
  PiModel m(p);
  for (double u : {-10.0, 5.0, 250.0}) EXPECT_DOUBLE_EQ(m.forward(u), 3e-9 * u);
}

TEST(PiParams, ValidationNamesTheField) {
  auto refused = [](const PiParams& p, const std::string& field) {
    try {
      p.validate();
      ADD_FAILURE() << "accepted; expected " << field;
    } catch (const ParameterError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
    EXPECT_THROW(PiModel{p}, ParameterError);
    EXPECT_THROW(PiInverse{p}, ParameterError);
  };
  PiParams p = single_play(1e-9, 10.0, 2e-9);
  EXPECT_NO_THROW(p.validate());
  PiParams q = p;
  q.count = 0;
  refused(q, "count");
  q.count = kPiMaxOperators + 1;
  refused(q, "count");
  q = p;
  q.weights[0] = 0.0;
  refused(q, "weights[0]");
  q.weights[0] = -1e-9;
  refused(q, "weights[0]");
  q = p;
  q.weights[1] = -1e-9;  // cumulative 0: the loading curve goes flat
  refused(q, "weights[1]");
  q.weights[1] = -0.5e-9;  // a negative weight that keeps it increasing is fine
  EXPECT_NO_THROW(q.validate());
  q = p;
  q.thresholds[1] = 0.0;
  refused(q, "thresholds[1]");
  q.thresholds[1] = std::numeric_limits<double>::quiet_NaN();
  refused(q, "thresholds[1]");
  q = p;
  q.thresholds[0] = 1.0;
  refused(q, "thresholds[0]");
  q = p;
  q.weights[1] = std::numeric_limits<double>::infinity();
  refused(q, "weights[1]");
}

TEST(PiParams, EvenThresholds) {
  const PiParams p = PiParams::with_even_thresholds(15, 250.0);
  EXPECT_EQ(p.count, 15u);
  EXPECT_EQ(p.thresholds[0], 0.0);
  EXPECT_NEAR(p.thresholds[14], 250.0 * 14.0 / 15.0, 1e-12);
  EXPECT_NEAR(p.thresholds[3] - p.thresholds[2], 250.0 / 15.0, 1e-12);
  EXPECT_THROW(PiParams::with_even_thresholds(0, 250.0), ParameterError);
  EXPECT_THROW(PiParams::with_even_thresholds(15, -1.0), ParameterError);
}

TEST(PiInverse, InverseOfInverseIsForward) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const PiParams p = random_params(rng, 1 + static_cast<std::size_t>(trial) % kPiMaxOperators);
    const PiParams back = inverse_pi_params(inverse_pi_params(p));
    for (std::size_t i = 0; i < p.count; ++i) {
      EXPECT_NEAR(back.thresholds[i], p.thresholds[i], 1e-12 * std::max(1.0, p.thresholds[i]));
      EXPECT_NEAR(back.weights[i], p.weights[i], 1e-12 * p.weights[0]);
    }
  }
}

// The inverse loading curve is the inverse function of the forward one: slopes 1/W_i between r'_i.
TEST(PiInverse, InverseLoadingCurve) {
  const PiParams p = single_play(1e-9, 10.0, 3e-9);
  const PiParams inv = inverse_pi_params(p);
  EXPECT_DOUBLE_EQ(inv.thresholds[1], 1e-9 * 10.0);  // r'_1 = w_0 (r_1 - r_0)
  EXPECT_DOUBLE_EQ(inv.weights[0], 1e9);
  EXPECT_DOUBLE_EQ(inv.weights[0] + inv.weights[1], 1.0 / 4e-9);
}

struct Errors {
  double inverse_of_forward = 0.0;  // [V]
  double forward_of_inverse = 0.0;  // [m]
};

Errors compositions(const PiParams& p, std::uint64_t seed, std::size_t n) {
  Errors e;
  {
    PiModel f(p);
    PiInverse inv(p);
    RandomRuns u(seed, 250.0);
    for (std::size_t k = 0; k < n; ++k) {
      const double x = u.next();
      e.inverse_of_forward = std::max(e.inverse_of_forward, std::abs(inv.inverse(f.forward(x)) - x));
    }
  }
  {
    PiModel f(p);
    PiInverse inv(p);
    PiModel probe(p);
    const double y_amp = probe.forward(250.0);  // the virgin curve at 250 V
    RandomRuns y(seed + 1, y_amp);
    for (std::size_t k = 0; k < n; ++k) {
      const double x = y.next();
      e.forward_of_inverse = std::max(e.forward_of_inverse, std::abs(f.forward(inv.inverse(x)) - x) / y_amp);
    }
  }
  return e;
}

TEST(PiInverse, ExactBothWaysOverManyReversalsPaper15) {
  const PiParams p = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  const Errors e = compositions(p, 7, kLong);
  EXPECT_LT(e.inverse_of_forward / 250.0, 1e-12);
  EXPECT_LT(e.forward_of_inverse, 1e-12);
}

TEST(PiInverse, ExactBothWaysRandomParameters) {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 20; ++trial) {
    const PiParams p = random_params(rng, 1 + static_cast<std::size_t>(trial) % kPiMaxOperators);
    const Errors e = compositions(p, 100 + static_cast<std::uint64_t>(trial), kLong / 20);
    EXPECT_LT(e.inverse_of_forward / 250.0, 1e-12) << trial;
    EXPECT_LT(e.forward_of_inverse, 1e-12) << trial;
  }
}

TEST(PiInverse, ResetMatchesForwardReset) {
  const PiParams p = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  PiModel f(p);
  PiInverse inv(p);
  f.reset(-120.0);
  inv.reset(f.output());
  EXPECT_NEAR(inv.output(), -120.0, 1e-12);
  RandomRuns u(3, 250.0);
  for (int k = 0; k < 10000; ++k) {
    const double x = u.next();
    EXPECT_NEAR(inv.inverse(f.forward(x)), x, 1e-10);
  }
}

// Both follow Masing's rule, so the MEM-matched PI operator equals the MEM model at the breakpoints:
// on the virgin curve at u = r_i and on the major-loop branch from -A at u = -A + 2 r_i.
TEST(PiParams, FromMemMatchesMemAtBreakpoints) {
  const MemParams mem = MemParams::paper_like();
  const PiParams p = pi_params_from_mem(mem, 15, 250.0);
  PiModel pi(p);
  MemModel model(mem);
  for (std::size_t i = 0; i < 15; ++i) {
    EXPECT_NEAR(pi.forward(p.thresholds[i]), model.forward(p.thresholds[i]), 1e-20) << i;
  }
  EXPECT_NEAR(pi.forward(250.0), model.forward(250.0), 1e-20);
  pi.forward(-250.0);
  model.forward(-250.0);
  for (std::size_t i = 0; i < 15; ++i) {
    const double u = -250.0 + 2.0 * p.thresholds[i];
    EXPECT_NEAR(pi.forward(u), model.forward(u), 1e-20) << i;
  }
  EXPECT_NEAR(pi.forward(250.0), model.forward(250.0), 1e-20);
  // In between it is piecewise linear: close, not equal.
  EXPECT_NEAR(pi.forward(240.0), model.forward(240.0), 5e-10);
}

TEST(PiModel, SetParamsKeepsOutputContinuous) {
  const PiParams a = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  MemParams other = MemParams::paper_like();
  other.c1 *= 1.2;
  const PiParams b = pi_params_from_mem(other, 10, 250.0);
  PiModel m(a);
  PiInverse inv(a);
  RandomRuns u(9, 250.0);
  for (int k = 0; k < 5000; ++k) inv.inverse(m.forward(u.next()));
  const double y = m.output();
  const double u_now = inv.output();
  m.set_params(b);
  inv.set_params(b);
  EXPECT_EQ(m.params().count, 10u);
  EXPECT_NEAR(m.forward(m.input()), y, 1e-21);
  EXPECT_NEAR(inv.inverse(y), u_now, 1e-9);
  EXPECT_NEAR(m.forward(m.input() + 0.01), y, 0.01 * 2e-8);
  EXPECT_THROW(m.set_params(PiParams{}), ParameterError);
}

TEST(PiRealTime, PerSampleCallsAllocateNothing) {
  const PiParams p = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  PiModel m(p);
  PiInverse inv(p);
  RandomRuns u(4, 250.0);
  testing::AllocationCounter counter;
  double sink = 0.0;
  for (int k = 0; k < 20000; ++k) sink += inv.inverse(m.forward(u.next()));
  m.set_params(p);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_TRUE(std::isnan(m.forward(std::numeric_limits<double>::quiet_NaN())));
}

}  // namespace
}  // namespace hystloop
