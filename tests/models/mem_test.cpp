// MEM / Ramberg–Osgood model of Strijbosch, Tiels & Oomen: the closed-form branches against (2)/(3)
// evaluated directly for the paper's input (1), Theorem 4's parameter map, Theorem 10 (the inverse
// driving the model reproduces the reference to rounding) over long signals with thousands of
// reversals, the reverse composition, seeded random parameters, validation, holds, jitter, the
// bumpless parameter swap and allocation-free per-sample calls.

#include "models/mem.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "models/model_concepts.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

static_assert(HysteresisForward<MemModel>);
static_assert(HysteresisInverse<MemInverse>);

constexpr double kPi = std::numbers::pi;
#if defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kLong = 100'000;  // the sanitizer build is ~20x slower
#else
constexpr std::size_t kLong = 1'000'000;
#endif

// The paper's input (1), sampled at 10 kHz.
double paper_input(double t) {
  return t <= 7.0 / 4.0 ? 250.0 * std::sin(2.0 * kPi * t) : 125.0 * std::sin(2.0 * kPi * t) - 125.0;
}

std::vector<double> paper_input_samples(double t_end, double dt = 1e-4) {
  std::vector<double> u;
  for (std::size_t k = 0; static_cast<double>(k) * dt <= t_end + 1e-12; ++k)
    u.push_back(paper_input(static_cast<double>(k) * dt));
  return u;
}

// Smooth random signal with holds: cosine-eased monotone moves between random levels in [lo, hi]
// (each next level may continue the direction or reverse it), with random holds in between.
class SmoothRandomSignal {
 public:
  SmoothRandomSignal(std::uint64_t seed, double lo, double hi)
      : rng_(seed), lo_(lo), hi_(hi), from_(0.5 * (lo + hi)), to_(from_) {}

  double next() {
    if (hold_left_ > 0) {
      --hold_left_;
      return to_;
    }
    if (k_ >= n_) start_move();
    ++k_;
    const double s = 0.5 * (1.0 - std::cos(kPi * static_cast<double>(k_) / static_cast<double>(n_)));
    const double x = k_ == n_ ? to_ : from_ + (to_ - from_) * s;
    if (k_ == n_ && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < 0.3) {
      hold_left_ = std::uniform_int_distribution<int>(1, 300)(rng_);
    }
    return x;
  }

 private:
  void start_move() {
    from_ = to_;
    to_ = std::uniform_real_distribution<double>(lo_, hi_)(rng_);
    n_ = std::uniform_int_distribution<int>(8, 400)(rng_);
    k_ = 0;
  }

  std::mt19937_64 rng_;
  double lo_, hi_, from_, to_;
  int n_ = 0, k_ = 0, hold_left_ = 0;
};

// Independent oracle: (2) until the first reversal, then (3) from the latest branching point,
// straight from the Ramberg–Osgood parameters. A reversal is a change of the sign of the last
// non-zero increment.
std::vector<double> ramberg_osgood_oracle(const RambergOsgoodParams& ro, const std::vector<double>& u) {
  std::vector<double> y(u.size());
  bool skeleton = true;
  int dir = 0;
  double u_i = 0.0, y_i = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (k > 0 && u[k] != u[k - 1]) {
      const int d = u[k] > u[k - 1] ? 1 : -1;
      if (dir != 0 && d != dir) {
        skeleton = false;
        u_i = u[k - 1];
        y_i = y[k - 1];
      }
      dir = d;
    }
    y[k] = skeleton ? ro.skeleton(u[k]) : ro.branch(u[k], u_i, y_i);
  }
  return y;
}

RambergOsgoodParams test_ro() {
  RambergOsgoodParams ro;
  ro.y_star = 1.25e-6;
  ro.u_star = 250.0;
  ro.alpha = 0.19;
  ro.gamma = 2.2;
  return ro;
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// ---- parameters ---------------------------------------------------------------------------------

void expect_refused(const MemParams& p, const std::string& field) {
  try {
    p.validate();
    ADD_FAILURE() << "accepted, expected a ParameterError on " << field;
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
  }
  EXPECT_THROW(MemModel{p}, ParameterError);
  EXPECT_THROW(MemInverse{p}, ParameterError);
}

TEST(MemParams, DefaultIsPaperLikeAndValid) {
  const MemParams p = MemParams::paper_like();
  EXPECT_NO_THROW(p.validate());
  // The scale documented in mem.hpp: a +-250 V major loop spans ~3.17 um, ~12 % of it wide at u = 0.
  const double stroke = p.branch_rise(500.0);
  EXPECT_NEAR(stroke, 3.17e-6, 0.01e-6);
  const double width = stroke - 2.0 * p.branch_rise(250.0);
  EXPECT_NEAR(width / stroke, 0.119, 0.001);
}

TEST(MemParams, RefusesBadValuesNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  MemParams p;
  p.c1 = 0.0;
  expect_refused(p, "c1");
  p.c1 = -5e-9;
  expect_refused(p, "c1");
  p.c1 = nan;
  expect_refused(p, "c1");
  p = {};
  p.c2 = -1e-12;
  expect_refused(p, "c2");
  p.c2 = inf;
  expect_refused(p, "c2");
  p = {};
  p.c3 = 0.0;
  expect_refused(p, "c3");
  p.c3 = -1.0;
  expect_refused(p, "c3");
  p.c3 = nan;
  expect_refused(p, "c3");
  p = {};
  p.c2 = 0.0;  // a linear spring is allowed
  EXPECT_NO_THROW(p.validate());
  EXPECT_THROW(MemModel(MemParams{}, -1.0), ParameterError);
  EXPECT_THROW(MemInverse(MemParams{}, nan), ParameterError);
}

TEST(MemParams, MessageNamesFieldAndValue) {
  MemParams p;
  p.c3 = -1.0;
  try {
    p.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("c3: must be > 0"), std::string::npos) << e.what();
  }
}

// Theorem 4 against the paper's branch (3) itself, not against the map's formula. By hand:
// y* = 1 um, u* = 50 V, alpha = 1, gamma = 2 make (3) on an ascending branch
//   y - y_i = 2 y* (p / 2u*) (1 + p / 2u*) = 2e-8 p + 2e-10 p^2  [m, p in V],
// so its slope is dy/dp = 2e-8 + 4e-10 p: M(p) = c1 + c2 p^c3 with c1 = 2e-8, c2 = 4e-10, c3 = 1
// (at p = 25 V: 3e-8 m/V; at 150 V: 8e-8 m/V). For gamma = 2.2 the slope of (3) is taken by
// central differences of (3) as printed, and the rise F(p) is (3) itself.
TEST(RambergOsgood, Theorem4AgainstTheBranchEquation3) {
  RambergOsgoodParams ro;
  ro.y_star = 1e-6, ro.u_star = 50.0, ro.alpha = 1.0, ro.gamma = 2.0;
  const MemParams m = ro.to_mem();
  EXPECT_NEAR(m.slope(25.0), 3e-8, 1e-22);
  EXPECT_NEAR(m.slope(150.0), 8e-8, 1e-22);
  EXPECT_NEAR(m.branch_rise(100.0), 2e-6 + 2e-6, 1e-20);  // 2e-8 * 100 + 2e-10 * 100^2
  const RambergOsgoodParams r = test_ro();
  auto eq3 = [&](double p) {  // (3): (y - y_i) / 2y* = (p / 2u*) (1 + alpha |p / 2u*|^(gamma - 1))
    const double x = p / (2.0 * r.u_star);
    return 2.0 * r.y_star * x * (1.0 + r.alpha * std::pow(std::abs(x), r.gamma - 1.0));
  };
  const MemParams mr = r.to_mem();
  for (double p : {3.0, 40.0, 170.0, 480.0}) {
    const double h = 1e-3 * p;
    const double slope = (eq3(p + h) - eq3(p - h)) / (2.0 * h);
    EXPECT_NEAR(mr.slope(p), slope, 1e-7 * slope) << p;  // central difference: O(h^2) ~ 1e-7 relative
    EXPECT_NEAR(mr.branch_rise(p), eq3(p), 1e-13 * eq3(p)) << p;
  }
}

TEST(RambergOsgood, Theorem4ParameterMapAndBack) {
  const RambergOsgoodParams ro = test_ro();
  const MemParams m = ro.to_mem();
  EXPECT_DOUBLE_EQ(m.c1, ro.y_star / ro.u_star);
  EXPECT_DOUBLE_EQ(m.c2, ro.y_star / ro.u_star * ro.alpha * ro.gamma / std::pow(2.0 * ro.u_star, ro.gamma - 1.0));
  EXPECT_DOUBLE_EQ(m.c3, ro.gamma - 1.0);
  const RambergOsgoodParams back = RambergOsgoodParams::from_mem(m, ro.u_star);
  EXPECT_NEAR(back.y_star, ro.y_star, 1e-15 * ro.y_star);
  EXPECT_NEAR(back.alpha, ro.alpha, 1e-14 * ro.alpha);
  EXPECT_NEAR(back.gamma, ro.gamma, 1e-15);
  // Any u* gives the same MEM parameters (the RO form has one redundant scale).
  const MemParams again = RambergOsgoodParams::from_mem(MemParams::paper_like(), 37.0).to_mem();
  EXPECT_NEAR(again.c1, MemParams::paper_like().c1, 1e-24);
  EXPECT_NEAR(again.c2, MemParams::paper_like().c2, 1e-26);
  EXPECT_NEAR(again.c3, MemParams::paper_like().c3, 1e-15);

  RambergOsgoodParams bad = ro;
  bad.gamma = 1.0;
  EXPECT_THROW(bad.to_mem(), ParameterError);
  bad = ro;
  bad.u_star = 0.0;
  EXPECT_THROW(bad.validate(), ParameterError);
  EXPECT_THROW(RambergOsgoodParams::from_mem(m, -1.0), ParameterError);
}

// Theorem 4 / (7): the slope of (3) along a branch is M(p); the slope of the skeleton (2) is
// M(2|u|) (Masing) — derived in mem.hpp, checked here by central differences of (2)/(3).
TEST(RambergOsgood, SlopesOfSkeletonAndBranchAreM) {
  const RambergOsgoodParams ro = test_ro();
  const MemParams m = ro.to_mem();
  for (double p : {1.0, 10.0, 73.0, 250.0, 499.0}) {
    const double h = 1e-3;
    const double branch_slope =
        (ro.branch(-250.0 + p + h, -250.0, 0.0) - ro.branch(-250.0 + p - h, -250.0, 0.0)) / (2 * h);
    EXPECT_NEAR(branch_slope, m.slope(p), 1e-7 * m.slope(p)) << p;
    const double u = 0.5 * p;
    const double skeleton_slope = (ro.skeleton(u + h) - ro.skeleton(u - h)) / (2 * h);
    EXPECT_NEAR(skeleton_slope, m.slope(2.0 * u), 1e-7 * m.slope(2.0 * u)) << p;
    // The closed forms themselves.
    EXPECT_NEAR(ro.branch(-250.0 + p, -250.0, 0.0), m.branch_rise(p), 1e-13 * m.branch_rise(p));
    EXPECT_NEAR(ro.skeleton(u), m.skeleton(u), 1e-13 * std::abs(m.skeleton(u)));
    EXPECT_NEAR(ro.skeleton(-u), m.skeleton(-u), 1e-13 * std::abs(m.skeleton(u)));
  }
}

TEST(MemParams, BranchRunInvertsBranchRise) {
  const MemParams m = MemParams::paper_like();
  EXPECT_EQ(m.branch_run(0.0), 0.0);
  for (double p : {1e-9, 1e-3, 0.5, 3.0, 100.0, 500.0, 1e4}) {
    EXPECT_NEAR(m.branch_run(m.branch_rise(p)), p, 4e-16 * p) << p;
  }
}

// ---- forward model against the paper's example -------------------------------------------------

TEST(MemModel, PaperInput1MatchesRambergOsgoodDirectly) {
  const RambergOsgoodParams ro = test_ro();
  const std::vector<double> u = paper_input_samples(3.0);
  const std::vector<double> expected = ramberg_osgood_oracle(ro, u);
  MemModel model(ro.to_mem());
  model.reset(u[0]);
  const double scale = max_abs(expected);
  double worst = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) worst = std::max(worst, std::abs(model.forward(u[k]) - expected[k]));
  EXPECT_LT(worst / scale, 1e-13);
  // Branching points of (1) on [0, 3] s: t = 0.25, 0.75, 1.25, 1.75, 2.25, 2.75 (Fig. 1).
  EXPECT_EQ(model.reversals(), 6u);
  EXPECT_FALSE(model.on_skeleton());
}

TEST(MemModel, SkeletonThenBranchesFigure2) {
  const MemParams m = MemParams::paper_like();
  MemModel model(m);
  // Skeleton to +250 V.
  for (int k = 0; k <= 250; ++k) EXPECT_NEAR(model.forward(k), m.skeleton(k), 1e-22);
  EXPECT_TRUE(model.on_skeleton());
  const double y_top = model.output();
  // First branch down to -250 V: y = y_top - F(250 - u); the slope just after the reversal is c1.
  const double y1 = model.forward(249.0);
  EXPECT_FALSE(model.on_skeleton());
  EXPECT_EQ(model.branch_origin_u(), 250.0);
  EXPECT_NEAR(y1, y_top - m.branch_rise(1.0), 1e-22);
  for (int k = 248; k >= -250; --k) model.forward(k);
  EXPECT_NEAR(model.output(), y_top - m.branch_rise(500.0), 1e-21);
  // Up again to +250 V: the major loop closes (Masing), y returns to y_top to rounding.
  for (int k = -249; k <= 250; ++k) model.forward(k);
  EXPECT_NEAR(model.output(), y_top - m.branch_rise(500.0) + m.branch_rise(500.0), 1e-21);
  EXPECT_NEAR(model.output(), y_top, 1e-20);
  EXPECT_EQ(model.reversals(), 2u);
}

// No Masing memory (as the paper). A closed minor loop does return to its start point (its two
// branches are the same F), but past it the input follows the branch started at its last reversal,
// not the outer branch it left, as a wiping-out (Masing memory) model would.
TEST(MemModel, MinorLoopFollowsNewBranchNotOuterOne) {
  const MemParams m = MemParams::paper_like();
  MemModel model(m), outer(m);
  model.reset_to_branch(-250.0, -1.6e-6);
  outer.reset_to_branch(-250.0, -1.6e-6);
  for (int k = -249; k <= 100; ++k) {
    model.forward(k);
    outer.forward(k);
  }
  for (int k = 99; k >= 0; --k) model.forward(k);
  const double y_0 = model.output();
  for (int k = 1; k <= 100; ++k) model.forward(k);
  EXPECT_NEAR(model.output(), outer.output(), 1e-21);  // the minor loop closes
  for (int k = 101; k <= 200; ++k) {
    model.forward(k);
    outer.forward(k);
  }
  EXPECT_NEAR(model.output(), y_0 + m.branch_rise(200.0), 1e-21);  // the branch from u = 0
  EXPECT_LT(model.output(), outer.output() - 1e-8);                // below the outer branch
  EXPECT_EQ(model.reversals(), 2u);
}

TEST(MemModel, HoldCreatesNoReversalAndDoesNotChangeTheBranch) {
  MemModel held, straight;
  for (int k = 0; k <= 200; ++k) {
    held.forward(k);
    straight.forward(k);
  }
  for (int k = 0; k < 10000; ++k) EXPECT_EQ(held.forward(200.0), straight.output());
  for (int k = 201; k <= 240; ++k) EXPECT_EQ(held.forward(k), straight.forward(k));
  EXPECT_EQ(held.reversals(), 0u);
  EXPECT_TRUE(held.on_skeleton());
  // A hold at a turning point: the direction is that of the last non-zero change.
  for (int k = 0; k < 500; ++k) held.forward(240.0);
  held.forward(239.0);
  EXPECT_EQ(held.reversals(), 1u);
  EXPECT_EQ(held.branch_origin_u(), 240.0);
}

TEST(MemModel, DeadbandIgnoresJitterButNotRealReversals) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);  // [V]
  MemModel paper, filtered(MemParams{}, 2.5e-3);
  for (int k = 0; k <= 100; ++k) {
    paper.forward(k);
    filtered.forward(k);
  }
  for (int k = 0; k < 1000; ++k) {
    const double u = 100.0 + jitter(rng);
    paper.forward(u);
    filtered.forward(u);
  }
  EXPECT_GT(paper.reversals(), 100u);  // the paper's model takes every wiggle as a branching point
  EXPECT_EQ(filtered.reversals(), 0u);
  // Continuing upwards, the filtered model is still on its skeleton; a real turn is still seen,
  // at the extremum (the highest jittered input), not at the sample that exposed it.
  for (int k = 101; k <= 150; ++k) filtered.forward(k);
  EXPECT_TRUE(filtered.on_skeleton());
  filtered.forward(149.999);
  EXPECT_EQ(filtered.reversals(), 0u);
  filtered.forward(149.0);
  EXPECT_EQ(filtered.reversals(), 1u);
  EXPECT_EQ(filtered.branch_origin_u(), 150.0);
}

TEST(MemModel, NonFiniteInputReturnsNanAndKeepsState) {
  MemModel model;
  model.forward(10.0);
  const double y = model.output();
  EXPECT_TRUE(std::isnan(model.forward(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_TRUE(std::isnan(model.forward(std::numeric_limits<double>::infinity())));
  EXPECT_EQ(model.output(), y);
  EXPECT_EQ(model.forward(10.0), y);
  MemInverse inv;
  inv.inverse(1e-7);
  const double u = inv.output();
  EXPECT_TRUE(std::isnan(inv.inverse(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(inv.inverse(1e-7), u);
}

// ---- Theorem 10: exact feedforward ---------------------------------------------------------------

struct Composition {
  double worst = 0.0;  // max |error|
  double scale = 0.0;  // max |signal|
  std::uint64_t reversals = 0;
};

inline double step(MemModel& model, double u) { return model.forward(u); }
inline double step(MemInverse& inverse, double y) { return inverse.inverse(y); }

// x -> a -> b -> x': both start virgin (reset) at matching points, b at a's output. Records the
// worst |x' - x| and the largest |x| (reversals are the caller's: it knows which one is the model).
template <class A, class B, class Signal>
Composition round_trip(A& a, B& b, Signal&& x_of, std::size_t n) {
  const double x0 = x_of();
  a.reset(x0);
  b.reset(a.output());
  Composition c;
  c.worst = std::abs(b.output() - x0);
  for (std::size_t k = 1; k < n; ++k) {
    const double x = x_of();
    c.worst = std::max(c.worst, std::abs(step(b, step(a, x)) - x));
    c.scale = std::max(c.scale, std::abs(x));
  }
  return c;
}

// y_d -> MemInverse -> MemModel -> y when inverse_first (both then count the same reversals),
// else u -> MemModel -> MemInverse -> u; the reversals recorded are the model's.
template <class Signal>
Composition mem_round_trip(bool inverse_first, const MemParams& p, Signal&& x_of, std::size_t n) {
  MemModel model(p);
  MemInverse inv(p);
  Composition c = inverse_first ? round_trip(inv, model, x_of, n) : round_trip(model, inv, x_of, n);
  c.reversals = model.reversals();
  if (inverse_first) {
    EXPECT_EQ(model.reversals(), inv.reversals());
  }
  return c;
}
template <class Signal>
Composition inverse_then_model(const MemParams& p, Signal&& y_d, std::size_t n) {
  return mem_round_trip(true, p, y_d, n);
}
template <class Signal>
Composition model_then_inverse(const MemParams& p, Signal&& u_in, std::size_t n) {
  return mem_round_trip(false, p, u_in, n);
}

TEST(MemTheorem10, RandomSmoothReferenceWithHolds) {
  SmoothRandomSignal sig(20240601, -1.6e-6, 1.6e-6);
  const Composition c = inverse_then_model(
      MemParams::paper_like(), [&] { return sig.next(); }, kLong);
  EXPECT_LT(c.worst / c.scale, 1e-12) << c.worst;
  EXPECT_GT(c.reversals, kLong / 500);  // thousands over 10^6 samples
  std::printf("[ info ] inverse->model: %zu samples, %llu reversals, max error %.3g m (%.3g of stroke)\n", kLong,
              static_cast<unsigned long long>(c.reversals), c.worst, c.worst / c.scale);
}

TEST(MemTheorem10, ReverseCompositionRandomSmoothInputWithHolds) {
  SmoothRandomSignal sig(777, -250.0, 250.0);
  const Composition c = model_then_inverse(
      MemParams::paper_like(), [&] { return sig.next(); }, kLong);
  EXPECT_LT(c.worst / c.scale, 1e-12) << c.worst;
  EXPECT_GT(c.reversals, kLong / 500);
}

// The paper's experiment (24): y_d = -1.6 um cos(2 pi t) at 10 kHz, both from the virgin state and
// from Theorem 10's start (a branching point at u = 0, y = y_d(0)).
TEST(MemTheorem10, PaperReference24) {
  const MemParams p = MemParams::paper_like();
  const std::size_t n = 100'000;  // 10 s, 20 reversals
  std::size_t k = 0;
  auto y_d = [&] { return -1.6e-6 * std::cos(2.0 * kPi * 1e-4 * static_cast<double>(k++)); };
  const Composition c = inverse_then_model(p, y_d, n);
  EXPECT_LT(c.worst / 1.6e-6, 1e-13);
  // 19 peaks in 10 s, plus t = 0: the virgin state at y0 < 0 was reached moving down, so rising
  // from it is a branching point.
  EXPECT_EQ(c.reversals, 20u);

  MemInverse inv(p);
  MemModel model(p);
  inv.reset_to_branch(-1.6e-6, 0.0);
  model.reset_to_branch(0.0, -1.6e-6);
  double worst = 0.0, u_min = 0.0, u_max = 0.0;
  k = 0;  // y_d counts the samples
  for (std::size_t i = 0; i < n; ++i) {
    const double y = y_d();
    const double u = inv.inverse(y);
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    worst = std::max(worst, std::abs(model.forward(u) - y));
  }
  EXPECT_LT(worst / 1.6e-6, 1e-13);
  // From u = 0 at the bottom the branch needs F^-1(3.2 um) ~ 504 V of travel: u in [0, ~504] V.
  EXPECT_NEAR(u_max, p.branch_run(3.2e-6), 1e-6);
  EXPECT_GE(u_min, 0.0);
}

TEST(MemTheorem10, PaperInput1InverseRecoversInput) {
  const std::vector<double> u = paper_input_samples(3.0);
  std::size_t k = 0;
  const Composition c = model_then_inverse(
      test_ro().to_mem(), [&] { return u[k++]; }, u.size());
  EXPECT_LT(c.worst / 250.0, 1e-13);
  EXPECT_EQ(c.reversals, 6u);
}

TEST(MemTheorem10, RandomParametersBothCompositions) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> log_c1(std::log(1e-9), std::log(2e-8));
  std::uniform_real_distribution<double> hysteresis(0.0, 3.0);  // M(500 V) / c1 - 1
  std::uniform_real_distribution<double> c3d(0.1, 3.0);
  const std::size_t n = kLong / 20;
  for (int trial = 0; trial < 20; ++trial) {
    MemParams p;
    p.c1 = std::exp(log_c1(rng));
    p.c3 = c3d(rng);
    p.c2 = p.c1 * hysteresis(rng) / std::pow(500.0, p.c3);
    if (trial == 0) p.c2 = 0.0;
    ASSERT_NO_THROW(p.validate());
    const double stroke = p.branch_rise(500.0) / 2.0;
    SmoothRandomSignal ys(1000 + static_cast<std::uint64_t>(trial), -stroke, stroke);
    const Composition a = inverse_then_model(
        p, [&] { return ys.next(); }, n);
    EXPECT_LT(a.worst / a.scale, 1e-12) << "trial " << trial << " c1 " << p.c1 << " c2 " << p.c2 << " c3 " << p.c3;
    SmoothRandomSignal us(2000 + static_cast<std::uint64_t>(trial), -250.0, 250.0);
    const Composition b = model_then_inverse(
        p, [&] { return us.next(); }, n);
    EXPECT_LT(b.worst / b.scale, 1e-12) << "trial " << trial << " c1 " << p.c1 << " c2 " << p.c2 << " c3 " << p.c3;
  }
}

TEST(MemInverse, ResetMatchesModelReset) {
  const MemParams p = MemParams::paper_like();
  for (double u0 : {-200.0, -1.0, 0.0, 3.0, 250.0}) {
    MemModel model(p);
    model.reset(u0);
    MemInverse inv(p);
    inv.reset(model.output());
    EXPECT_NEAR(inv.output(), u0, 1e-13 * std::max(1.0, std::abs(u0)));
    EXPECT_EQ(inv.direction(), model.direction());
  }
}

TEST(MemInverse, HoldAndJitterWithinDeadband) {
  MemInverse paper, filtered(MemParams{}, 1e-12);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-4e-13, 4e-13);  // [m]
  for (int k = 0; k <= 100; ++k) {
    paper.inverse(1e-8 * k);
    filtered.inverse(1e-8 * k);
  }
  const double u_top = filtered.output();
  for (int k = 0; k < 5000; ++k) EXPECT_EQ(paper.inverse(1e-6), u_top);  // a hold is a hold
  for (int k = 0; k < 1000; ++k) {
    const double y = 1e-6 + jitter(rng);
    paper.inverse(y);
    EXPECT_LE(filtered.inverse(y), u_top + 1e-3);
  }
  EXPECT_GT(paper.reversals(), 100u);
  EXPECT_EQ(filtered.reversals(), 0u);
  // A model driven by the filtered inverse sees no reversal either.
  MemModel model;
  MemInverse again(MemParams{}, 1e-12);
  for (int k = 0; k <= 100; ++k) model.forward(again.inverse(1e-8 * k));
  std::mt19937_64 rng2(5);
  for (int k = 0; k < 1000; ++k) EXPECT_NEAR(model.forward(again.inverse(1e-6 + jitter(rng2))), 1e-6, 1e-12);
  EXPECT_EQ(model.reversals(), 0u);
}

// ---- bumpless parameter swap ---------------------------------------------------------------------

TEST(MemSetParams, ModelOutputContinuousMidBranchAndOnSkeleton) {
  MemParams other;
  other.c1 = 4.0e-9;
  other.c2 = 4.0e-12;
  other.c3 = 1.1;
  for (bool on_branch : {false, true}) {
    MemModel model;
    for (int k = 0; k <= 200; ++k) model.forward(k);
    if (on_branch) {
      for (int k = 199; k >= 50; --k) model.forward(k);
    }
    EXPECT_EQ(model.on_skeleton(), !on_branch);
    const double y = model.output();
    model.set_params(other);
    EXPECT_EQ(model.params().c1, other.c1);
    EXPECT_NEAR(model.forward(model.input()), y, 1e-21);
    const double u = model.input() + (on_branch ? -0.1 : 0.1);
    EXPECT_NEAR(model.forward(u), y + (on_branch ? -1.0 : 1.0) * 0.1 * model.params().slope(on_branch ? 150.0 : 400.0),
                1e-13);
    EXPECT_EQ(model.on_skeleton(), !on_branch);
  }
  EXPECT_THROW(MemModel().set_params(MemParams{0.0, 1.0, 1.0}), ParameterError);
}

TEST(MemSetParams, InverseOutputContinuousMidBranch) {
  MemParams other;
  other.c1 = 4.0e-9;
  other.c2 = 4.0e-12;
  other.c3 = 1.1;
  MemInverse inv;
  for (int k = 0; k <= 100; ++k) inv.inverse(1.5e-8 * k);
  for (int k = 99; k >= 20; --k) inv.inverse(1.5e-8 * k);
  const double u = inv.output();
  const double p = u - inv.branch_origin_u();  // < 0: on a descending branch
  inv.set_params(other);
  const double dy = -1e-10;
  EXPECT_NEAR(inv.inverse(inv.reference() + dy), u + dy / other.slope(-p), 1e-6);
}

// The compensator's use: swap the parameters at every reversal while running. The model swapped at
// the same sample stays the exact inverse, and the next u differs from what the old parameters
// would have given by no more than the slope change accounts for (no jump).
TEST(MemSetParams, SwapsAtReversalsKeepThePairExact) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> factor(0.8, 1.25);
  SmoothRandomSignal sig(3, -1.5e-6, 1.5e-6);
  MemInverse inv;
  MemModel model;
  inv.reset(0.0);
  model.reset(0.0);
  double worst = 0.0, worst_jump = 0.0;
  std::uint64_t seen = 0, swaps = 0;
  bool compare_next = false;
  MemInverse unswapped = inv;
  for (std::size_t k = 0; k < 100'000; ++k) {
    const double y = sig.next();
    const double u_prev = inv.output();
    const double u = inv.inverse(y);
    worst = std::max(worst, std::abs(model.forward(u) - y));
    if (compare_next) {
      const double u_old = unswapped.inverse(y);
      // Parameters change by <= 25 % each (the slope by < 2x): the step may change by that much.
      if (u_old != u_prev) worst_jump = std::max(worst_jump, std::abs(u - u_old) / std::abs(u_old - u_prev));
      compare_next = false;
    }
    if (inv.reversals() != seen) {
      seen = inv.reversals();
      MemParams p = MemParams::paper_like();
      p.c1 *= factor(rng);
      p.c2 *= factor(rng);
      p.c3 *= factor(rng);
      unswapped = inv;
      inv.set_params(p);
      model.set_params(p);
      compare_next = true;
      ++swaps;
    }
  }
  EXPECT_GT(swaps, 100u);
  EXPECT_LT(worst / 1.5e-6, 1e-12);
  EXPECT_LT(worst_jump, 1.0);
}

// ---- real-time properties -------------------------------------------------------------------------

TEST(MemRealTime, PerSampleCallsAllocateNothing) {
  MemModel model;
  MemInverse inv;
  SmoothRandomSignal sig(8, -1.6e-6, 1.6e-6);
  std::vector<double> ys(20000);
  for (double& y : ys) y = sig.next();
  testing::AllocationCounter counter;
  double sink = 0.0;
  for (double y : ys) sink += model.forward(inv.inverse(y));
  MemParams p;
  p.c1 = 6e-9;
  model.set_params(p);  // the swap too
  inv.set_params(p);
  model.reset(0.0);
  inv.reset(0.0);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

// A stage measured partway along a branch (an identification input ended there) is continued on
// that branch: driving the model with the inverse's output reproduces the reference exactly, in
// both directions, and the first command equals the measured voltage (no step, no spurious branch).
TEST(MemInverse, ContinueBranchPicksUpAStageMeasuredOnItsBranch) {
  for (const double away : {+1.0, -1.0}) {
    MemModel plant;
    for (double u = 0.0; u > -320.0; u -= 1.0) plant.forward(u);  // down to the branching point
    plant.forward(-320.0);
    double u_now = -320.0;
    for (; u_now < -223.0; u_now += 0.7) plant.forward(u_now);  // up its branch: the last input
    const double y_now = plant.output();
    const double u_last = plant.input();
    MemInverse inverse;
    inverse.continue_branch(-320.0, u_last, y_now);
    EXPECT_EQ(inverse.inverse(y_now), u_last);
    EXPECT_EQ(inverse.direction(), 1);
    double worst = 0.0;
    for (int k = 1; k <= 2000; ++k) {  // the reference moves on (away = +1) or turns back (-1)
      const double y_ref = y_now + away * 4e-10 * k;
      worst = std::max(worst, std::abs(plant.forward(inverse.inverse(y_ref)) - y_ref));
    }
    EXPECT_LT(worst, 1e-15) << "reference moving " << (away > 0 ? "on" : "back");
  }
}

}  // namespace
}  // namespace hystloop
