#include "models/linear_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "models/second_order_stage.hpp"
#include "models/stage_inverse.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"

namespace hystloop {
namespace {

using Complex = std::complex<double>;
using Root = LinearStageSpec::Root;
using Mode = LinearStageSpec::Mode;
constexpr double kDt = 1e-4;  // the bridge's tick
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Two lightly damped modes: 780 Hz, zeta 0.03 (70 % of the DC gain) and 2.4 kHz, zeta 0.02.
const std::vector<Mode> kTwoModes{{780.0, 0.03, 0.7}, {2400.0, 0.02, 0.3}};

// The same stage as zeros / poles [Hz] and as polynomials in s, written out by hand.
struct TwoModeForms {
  std::vector<double> num, den;  // highest power first
  std::vector<Root> zeros, poles;
};
TwoModeForms two_mode_forms() {
  TwoModeForms f;
  double d[2][3];  // s^2 + 2 z w s + w^2
  for (int i = 0; i < 2; ++i) {
    const double w = kTwoPi * kTwoModes[static_cast<std::size_t>(i)].frequency_hz;
    const double z = kTwoModes[static_cast<std::size_t>(i)].damping_ratio;
    d[i][0] = 1.0;
    d[i][1] = 2.0 * z * w;
    d[i][2] = w * w;
    f.poles.push_back({-z * w / kTwoPi, w * std::sqrt(1.0 - z * z) / kTwoPi});
  }
  const double g0 = 0.7 * d[0][2], g1 = 0.3 * d[1][2];
  f.num = {g0 * d[1][0] + g1 * d[0][0], g0 * d[1][1] + g1 * d[0][1], g0 * d[1][2] + g1 * d[0][2]};
  f.den = {1.0, d[0][1] + d[1][1], d[0][2] + d[1][2] + d[0][1] * d[1][1], d[0][1] * d[1][2] + d[1][1] * d[0][2],
           d[0][2] * d[1][2]};
  const Complex disc = std::sqrt(Complex(f.num[1] * f.num[1] - 4.0 * f.num[0] * f.num[2], 0.0));
  const Complex z0 = (-f.num[1] + disc) / (2.0 * f.num[0]);
  f.zeros.push_back({z0.real() / kTwoPi, std::abs(z0.imag()) / kTwoPi});
  return f;
}

TEST(LinearStage, TheThreeContinuousFormsGiveTheSameResponseWithUnitDcGain) {
  const TwoModeForms f = two_mode_forms();
  const LinearStageSpec modes = LinearStageSpec::sum_of_modes(kTwoModes);
  const LinearStageSpec tf = LinearStageSpec::transfer_function(f.num, f.den);
  const LinearStageSpec zpk = LinearStageSpec::zero_pole(f.zeros, f.poles);
  for (const LinearStageSpec* s : {&modes, &tf, &zpk}) {
    EXPECT_EQ(s->order(), 4);
    EXPECT_NEAR(std::abs(s->frequency_response(0.0) - 1.0), 0.0, 1e-12);
  }
  // A printed gain is ignored: the polynomials times 3 are the same stage.
  std::vector<double> num3 = f.num;
  for (double& v : num3) v *= 3.0;
  const LinearStageSpec tf3 = LinearStageSpec::transfer_function(num3, f.den);
  for (const double hz : {1.0, 100.0, 500.0, 780.0, 1500.0, 2400.0, 4000.0, 20000.0}) {
    const Complex g = modes.frequency_response(hz);
    EXPECT_LT(std::abs(tf.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
    EXPECT_LT(std::abs(zpk.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
    EXPECT_LT(std::abs(tf3.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
  }
  // The resonance is there: 1 / (2 zeta) times the mode's share, give or take the other mode.
  EXPECT_GT(std::abs(modes.frequency_response(780.0)), 0.7 / (2.0 * 0.03));
  // The delay is a pure phase.
  LinearStageSpec delayed = modes;
  delayed.delay_s = 1.5 * kDt;
  const Complex ratio = delayed.frequency_response(1000.0) / modes.frequency_response(1000.0);
  EXPECT_NEAR(std::abs(ratio), 1.0, 1e-12);
  EXPECT_NEAR(std::arg(ratio), -kTwoPi * 1000.0 * 1.5 * kDt, 1e-12);
}

TEST(LinearStage, EightStatesAsPolynomialsMatchTheirModesAndAnOverdampedModeIsTwoRealPoles) {
  const std::vector<Mode> modes{{300.0, 0.05, 0.4}, {900.0, 1.5, 0.3}, {1700.0, 0.02, 0.2}, {3100.0, 0.01, 0.1}};
  // The polynomials of the sum, written out: num = sum_i w_i wn_i^2 prod_{j != i} D_j, den = prod D_j.
  auto times = [](const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> c(a.size() + b.size() - 1, 0.0);
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
    return c;
  };
  std::vector<double> den{1.0}, num(7, 0.0);
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const double w = kTwoPi * modes[i].frequency_hz;
    den = times(den, {1.0, 2.0 * modes[i].damping_ratio * w, w * w});
    std::vector<double> term{modes[i].weight * w * w};
    for (std::size_t j = 0; j < modes.size(); ++j) {
      if (j == i) continue;
      const double wj = kTwoPi * modes[j].frequency_hz;
      term = times(term, {1.0, 2.0 * modes[j].damping_ratio * wj, wj * wj});
    }
    for (std::size_t k = 0; k < term.size(); ++k) num[k] += term[k];
  }
  const LinearStageSpec a = LinearStageSpec::sum_of_modes(modes);
  const LinearStageSpec b = LinearStageSpec::transfer_function(num, den);
  EXPECT_EQ(b.order(), 8);
  for (const double hz : {0.0, 50.0, 300.0, 900.0, 1700.0, 3100.0, 4900.0}) {
    const Complex g = a.frequency_response(hz);
    EXPECT_LT(std::abs(b.frequency_response(hz) - g), 1e-8 * std::abs(g)) << hz;
  }
  const DiscreteLinearStage da = discretise(a, kDt), db = discretise(b, kDt);
  for (const double hz : {0.0, 300.0, 1700.0, 4900.0}) {
    const Complex g = da.frequency_response(hz);
    EXPECT_LT(std::abs(db.frequency_response(hz) - g), 1e-8 * std::abs(g)) << hz;
  }
  // zeta 1.5 at 900 Hz: poles e^{-wn (1.5 +- sqrt(1.25)) dt}, real.
  int real_poles = 0;
  for (Eigen::Index i = 0; i < da.poles.size(); ++i) real_poles += da.poles(i).imag() == 0.0 ? 1 : 0;
  EXPECT_EQ(real_poles, 2);
}

TEST(LinearStage, APureDelayShiftsTheCommandByItsWholeTicks) {
  // No dynamics, 2.5 ticks: the position at the end of tick k is the command of tick k - 2 (the
  // fraction only shows between tick ends).
  const DiscreteLinearStage s = discretise(LinearStageSpec::zero_pole({}, {}, 2.5 * kDt), kDt);
  EXPECT_EQ(s.delay_ticks, 2);
  LinearStageSimulator sim(s);
  std::vector<double> w(100);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    w[static_cast<std::size_t>(k)] = u(rng);
    const double y = sim.step(w[static_cast<std::size_t>(k)]);
    EXPECT_NEAR(y, k >= 2 ? w[static_cast<std::size_t>(k - 2)] : 0.0, 1e-15) << k;
  }
}

TEST(LinearStage, EachSampledFormHasUnitDcGainAndTheSamePolesAndZeros) {
  const TwoModeForms f = two_mode_forms();
  for (const double delay : {0.0, 1.5 * kDt, 3.0 * kDt}) {
    const DiscreteLinearStage a = discretise(LinearStageSpec::sum_of_modes(kTwoModes, delay), kDt);
    const DiscreteLinearStage b = discretise(LinearStageSpec::transfer_function(f.num, f.den, delay), kDt);
    const DiscreteLinearStage c = discretise(LinearStageSpec::zero_pole(f.zeros, f.poles, delay), kDt);
    for (const DiscreteLinearStage* s : {&a, &b, &c}) {
      EXPECT_NEAR(s->dc_gain(), 1.0, 1e-11) << delay;
      EXPECT_NEAR(std::abs(s->frequency_response(0.0) - 1.0), 0.0, 1e-11) << delay;
      EXPECT_EQ(s->delay_ticks, delay == 3.0 * kDt ? 3 : 1 * (delay > 0.0));
      EXPECT_EQ(s->states(), delay == 1.5 * kDt ? 5 : 4);
    }
    for (const double hz : {10.0, 780.0, 2400.0, 4999.0}) {
      const Complex g = a.frequency_response(hz);
      EXPECT_LT(std::abs(b.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
      EXPECT_LT(std::abs(c.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
    }
  }
}

TEST(LinearStage, BanningsSecondOrderAgreesWithDiscretiseZoh) {
  for (const SecondOrderStageParams p :
       {SecondOrderStageParams{}, SecondOrderStageParams{4e7, 6e3}, SecondOrderStageParams{3e8, 1.5e3}}) {
    const DiscreteStage banning = discretise_zoh(p, kDt);
    const DiscreteLinearStage s = discretise(LinearStageSpec::second_order(p.k, p.c), kDt);
    // Y_k = -a1 Y_{k-1} - a2 Y_{k-2} + b1 w_k + b2 w_{k-1}: the same convention, no delay.
    // In z^-1 the rational part is biproper: its second zero is at 0.
    ASSERT_EQ(s.numerator.size(), 3);
    ASSERT_EQ(s.denominator.size(), 3);
    EXPECT_EQ(s.delay_ticks, 0);
    EXPECT_NEAR(s.numerator(0), banning.b1, 1e-13 * std::abs(banning.b1)) << p.k;
    EXPECT_NEAR(s.numerator(1), banning.b2, 1e-13 * std::abs(banning.b1)) << p.k;
    EXPECT_NEAR(s.numerator(2), 0.0, 1e-13 * std::abs(banning.b1)) << p.k;
    EXPECT_NEAR(s.denominator(0), 1.0, 1e-15);
    EXPECT_NEAR(s.denominator(1), banning.a1, 1e-13) << p.k;
    EXPECT_NEAR(s.denominator(2), banning.a2, 1e-13) << p.k;
    ASSERT_EQ(s.zeros.size(), 2);
    const bool first = std::abs(s.zeros(0)) > std::abs(s.zeros(1));
    EXPECT_NEAR(std::abs(s.zeros(first ? 0 : 1) - banning.sampling_zero()), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(s.zeros(first ? 1 : 0)), 0.0, 1e-12);
    // Stepped side by side with SecondOrderStage.
    LinearStageSimulator sim(s);
    SecondOrderStage stage(p);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> w(-1.0, 1.0);
    double worst = 0.0;
    for (int k = 0; k < 2000; ++k) {
      const double wk = w(rng);
      worst = std::max(worst, std::abs(sim.step(wk) - stage.step(wk, kDt)));
    }
    EXPECT_LT(worst, 1e-12) << p.k;
  }
}

TEST(LinearStage, AFirstOrderStageDelayedByOneAndAHalfTicksFollowsItsClosedForm) {
  // a / (s + a), input delayed by tau = 1.5 dt, a unit step applied from tick 0: the input reaches
  // the stage at tau, so y(t) = 1 - e^{-a (t - tau)} for t >= tau, and y_k = y((k + 1) dt).
  for (const double hz : {300.0, 2000.0}) {
    const double a = kTwoPi * hz, tau = 1.5 * kDt;
    const DiscreteLinearStage s = discretise(LinearStageSpec::zero_pole({}, {{-hz, 0.0}}, tau), kDt);
    EXPECT_EQ(s.delay_ticks, 1);
    EXPECT_EQ(s.states(), 2);
    LinearStageSimulator sim(s);
    sim.reset(0.0);
    for (int k = 0; k < 50; ++k) {
      const double t = (k + 1) * kDt;
      const double expected = t < tau ? 0.0 : 1.0 - std::exp(-a * (t - tau));
      EXPECT_NEAR(sim.step(1.0), expected, 1e-14) << hz << " Hz, tick " << k;
    }
  }
}

TEST(LinearStage, SampledResponseIsTheContinuousOneTimesTheHoldAtLowFrequency) {
  // At low frequency the ZOH model is the continuous response (delay included) times the hold,
  // sin(w dt / 2) / (w dt / 2) e^{+i w dt / 2}: y_k is taken at the end of the tick over which w_k
  // is held, so against the index of w_k it is half a tick ahead of the hold's centre.
  for (const double delay : {0.0, 1.5 * kDt, 7.25 * kDt}) {
    const LinearStageSpec spec = LinearStageSpec::sum_of_modes(kTwoModes, delay);
    const DiscreteLinearStage s = discretise(spec, kDt);
    for (const double hz : {1.0, 10.0, 100.0}) {
      const double x = 0.5 * kTwoPi * hz * kDt;
      const Complex hold = std::sin(x) / x * std::polar(1.0, x);
      const Complex expected = spec.frequency_response(hz) * hold;
      // What aliases back grows like f: measured 1.6e-5 at 100 Hz without delay, 4.3e-4 with 7.25
      // ticks (a fraction breaks the cancellation of the aliases at +-n / dt).
      EXPECT_LT(std::abs(s.frequency_response(hz) - expected), 6e-6 * hz * std::abs(expected)) << delay << " " << hz;
    }
  }
}

TEST(LinearStage, ADiscreteModelRoundTripsThroughItsCoefficients) {
  const DiscreteLinearStage s = discretise(LinearStageSpec::sum_of_modes(kTwoModes, 2.0 * kDt), kDt);
  std::vector<double> num(s.numerator.begin(), s.numerator.end()), den(s.denominator.begin(), s.denominator.end());
  for (double& v : num) v *= -2.5;  // a printed gain is ignored, its sign included
  const DiscreteLinearStage back = discretise(LinearStageSpec::discrete(num, den, kDt), kDt);
  EXPECT_EQ(back.delay_ticks, 2);  // the numerator's two leading zeros
  for (const double hz : {0.0, 10.0, 780.0, 2400.0, 4999.0}) {
    const Complex g = s.frequency_response(hz);
    EXPECT_LT(std::abs(back.frequency_response(hz) - g), 1e-9 * std::abs(g)) << hz;
  }
  LinearStageSimulator a(s), b(back);
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const double w = std::sin(0.05 * k) + (k % 7 == 0 ? 0.3 : 0.0);
    worst = std::max(worst, std::abs(a.step(w) - b.step(w)));
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(LinearStage, RefusalsNameTheField) {
  using testing::refused_field;
  auto refuses = [](const LinearStageSpec& s) { return refused_field([&] { s.validate(kDt); }); };
  EXPECT_EQ(refuses(LinearStageSpec::zero_pole({}, {{-100.0, 0.0}, {10.0, 500.0}})), "stage.poles[1]");
  EXPECT_EQ(refuses(LinearStageSpec::zero_pole({}, {{0.0, 500.0}})), "stage.poles[0]");  // marginal
  EXPECT_EQ(refuses(LinearStageSpec::zero_pole({{-5.0, 0.0}, {-6.0, 0.0}}, {{-100.0, 0.0}})), "stage.zeros");
  EXPECT_EQ(refuses(LinearStageSpec::zero_pole({{0.0, 0.0}}, {{-100.0, 0.0}})), "stage.zeros[0]");  // DC gain 0
  std::vector<Root> many(9, Root{-50.0, 1000.0});                                                   // 18 states
  EXPECT_EQ(refuses(LinearStageSpec::zero_pole({}, many)), "stage.poles");
  many.resize(8);  // 16 states: accepted
  EXPECT_NO_THROW(LinearStageSpec::zero_pole({}, many).validate(kDt));
  EXPECT_EQ(refuses(LinearStageSpec::transfer_function({1.0, 0.0, 1.0}, {1.0, 1.0})), "stage.numerator_s");
  EXPECT_EQ(refuses(LinearStageSpec::transfer_function({1.0}, {1.0, -1.0, 1e6})), "stage.denominator_s");
  EXPECT_EQ(refuses(LinearStageSpec::transfer_function({1.0}, {1.0, 1.0, 0.0})), "stage.denominator_s");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes({{780.0, 0.0, 1.0}})), "stage.modes[0].damping_ratio");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes({{780.0, 0.1, 1.0}, {-1.0, 0.1, 1.0}})),
            "stage.modes[1].frequency_hz");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes({{780.0, 0.1, 1.0}, {900.0, 0.1, -1.0}})), "stage.modes");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes(kTwoModes, -kDt)), "stage.delay_s");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes(kTwoModes, 50.5 * kDt)), "stage.delay_s");
  EXPECT_EQ(refuses(LinearStageSpec::sum_of_modes(kTwoModes, std::nan(""))), "stage.delay_s");
  EXPECT_NO_THROW(LinearStageSpec::sum_of_modes(kTwoModes, 50.0 * kDt).validate(kDt));
  EXPECT_EQ(refuses(LinearStageSpec::discrete({0.5, 0.5}, {1.0, -0.5}, 2.0 * kDt)), "stage.discrete_dt_s");
  EXPECT_EQ(refuses(LinearStageSpec::discrete({0.5, 0.5}, {1.0, -0.5}, kDt, 0.5 * kDt)), "stage.delay_s");
  EXPECT_EQ(refuses(LinearStageSpec::discrete({0.5, 0.5}, {1.0, -1.0}, kDt)), "stage.denominator_zinv");
  EXPECT_EQ(refuses(LinearStageSpec::discrete({0.5, -0.5}, {1.0, -0.5}, kDt)), "stage.numerator_zinv");
  EXPECT_EQ(refused_field([] { LinearStageSpec::second_order(1.17e8, 2.03e3).validate(0.0); }), "dt_s");
  // The message says why.
  try {
    LinearStageSpec::zero_pole({}, {{-100.0, 0.0}, {10.0, 500.0}}).validate(kDt);
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("unstable pole"), std::string::npos) << e.what();
  }
  // Non-minimum-phase zeros are accepted.
  EXPECT_NO_THROW(LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-100.0, 1000.0}}).validate(kDt));
}

TEST(LinearStageSimulator, RestsWhereResetHoldsOnNonFiniteInputAndStepsWithoutAllocating) {
  const DiscreteLinearStage s = discretise(LinearStageSpec::sum_of_modes(kTwoModes, 2.5 * kDt), kDt);
  LinearStageSimulator sim(s);
  sim.reset(0.4e-6);
  for (int k = 0; k < 20; ++k) EXPECT_NEAR(sim.step(0.4e-6), 0.4e-6, 1e-18);
  LinearStageSimulator twin = sim;
  EXPECT_TRUE(std::isnan(sim.step(std::nan(""))));
  EXPECT_TRUE(std::isnan(sim.step(std::numeric_limits<double>::infinity())));
  for (int k = 0; k < 20; ++k) EXPECT_EQ(sim.step(1e-6 * k), twin.step(1e-6 * k));
  testing::AllocationCounter counter;
  double sum = 0.0;
  for (int k = 0; k < 1000; ++k) sum += sim.step(1e-9 * std::sin(0.01 * k));
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace hystloop
