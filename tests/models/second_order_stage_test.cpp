// Banning's second-order stage (28)-(29), Table 2: the exact zero-order-hold discretisation
// against the continuous closed forms and a much finer integrator, validation, properties.

#include "models/second_order_stage.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>

#include "core/errors.hpp"
#include "models/coleman_hodgdon_theory.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"
#include "support/sanitized.hpp"

namespace hystloop {
namespace {

constexpr double kPi = std::numbers::pi;
using testing::kSanitized;

// Least-squares fit of y = p cos(wt) + q sin(wt) + r; returns hypot(p, q).
double fitted_amplitude(const std::vector<double>& t, const std::vector<double>& y, double omega) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(t.size()), 3);
  Eigen::VectorXd v(static_cast<Eigen::Index>(t.size()));
  for (std::size_t i = 0; i < t.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    m(r, 0) = std::cos(omega * t[i]);
    m(r, 1) = std::sin(omega * t[i]);
    m(r, 2) = 1.0;
    v(r) = y[i];
  }
  const Eigen::Vector3d c = m.colPivHouseholderQr().solve(v);
  return std::hypot(c(0), c(1));
}

// Stationary amplitude of y for w = sin(2 pi f t) sampled every dt (after 40 ms of settling; the
// envelope decays as e^{-c t / 2}, e^{-40} by then), fitted over 0.1 s.
double simulated_gain(const SecondOrderStageParams& p, double f, double dt) {
  SecondOrderStage stage(p);
  const auto settle = static_cast<int>(std::lround(0.04 / dt));
  const auto window = static_cast<int>(std::lround(0.1 / dt));
  std::vector<double> t;
  std::vector<double> y;
  const double omega = 2.0 * kPi * f;
  for (int i = 0; i < settle + window; ++i) {
    const double ti = i * dt;
    const double yi = stage.step(std::sin(omega * ti), dt);  // held over [ti, ti + dt], read at ti + dt
    if (i >= settle) {
      t.push_back(ti + dt);
      y.push_back(yi);
    }
  }
  return fitted_amplitude(t, y, omega);
}

// The ZOH-equivalent transfer function written from the closed-form step response samples
// s_n = 1 - r^n (cos n th + (sigma / wd) sin n th), r = e^{-sigma dt}, th = wd dt:
// G_d(z) = (1 - 1/z) Z{s_n}. Independent of the matrix exponential used by the class.
double zoh_gain(const SecondOrderStageParams& p, double omega, double dt) {
  const double sigma = 0.5 * p.c;
  const double wd = std::sqrt(p.k - sigma * sigma);
  const double r = std::exp(-sigma * dt);
  const double th = wd * dt;
  const std::complex<double> z = std::polar(1.0, omega * dt);
  const std::complex<double> den = z * z - 2.0 * r * std::cos(th) * z + r * r;
  const std::complex<double> s =
      z / (z - 1.0) - z * (z - r * std::cos(th)) / den - (sigma / wd) * z * r * std::sin(th) / den;
  return std::abs((1.0 - 1.0 / z) * s);
}

TEST(SecondOrderStageParams, DefaultsAreTable2) {
  const SecondOrderStageParams p;
  EXPECT_DOUBLE_EQ(p.k, 1.17e8);
  EXPECT_DOUBLE_EQ(p.c, 2.03e3);
  EXPECT_NEAR(p.natural_frequency() / (2.0 * kPi), 1721.5, 0.1);  // the 1.7 kHz resonance
  EXPECT_NEAR(p.damping_ratio(), 0.0938, 1e-4);
}

TEST(SecondOrderStageParams, ValidationNamesTheField) {
  SecondOrderStageParams p;
  p.k = -1.0;
  const std::optional<ParameterError> e = testing::thrown<ParameterError>([&] { p.validate(); });
  ASSERT_TRUE(e) << "no throw";
  EXPECT_EQ(e->field(), "k");
  EXPECT_NE(std::string(e->what()).find("k: must be > 0 (got -1)"), std::string::npos) << e->what();
  p = {};
  p.c = std::nan("");
  EXPECT_EQ(testing::refused_field([&] { p.validate(); }), "c");
  EXPECT_THROW(SecondOrderStage{p}, ParameterError);
}

// Unit-step response at the 10 kHz rate against the continuous closed form
// y(t) = 1 - e^{-sigma t} (cos wd t + sigma / wd sin wd t): ZOH is exact for a held input.
TEST(SecondOrderStage, StepResponseMatchesTheClosedFormAtTheSamples) {
  const SecondOrderStageParams p;
  SecondOrderStage stage(p);
  const double dt = 100e-6;
  const double sigma = 0.5 * p.c;
  const double wd = std::sqrt(p.k - sigma * sigma);
  double worst = 0.0;
  double peak = 0.0;
  for (int i = 1; i <= 200; ++i) {
    const double t = i * dt;
    const double y = stage.step(1.0, dt);
    const double expected = 1.0 - std::exp(-sigma * t) * (std::cos(wd * t) + sigma / wd * std::sin(wd * t));
    worst = std::max(worst, std::abs(y - expected));
    peak = std::max(peak, y);
  }
  std::printf("stage unit step at dt = 100 us vs closed form: max |error| = %.3g\n", worst);
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(peak, 1.5);  // lightly damped: ~74 % overshoot in continuous time
  EXPECT_NEAR(stage.output(), 1.0, 1e-6);
  EXPECT_NEAR(stage.velocity(), 0.0, 1e-3);
}

// Discretisation error against a much finer step: the same held input sequence integrated by RK4
// with 1000 substeps per sample (error ~1e-15) agrees with the single ZOH step per sample.
TEST(SecondOrderStage, ZohStepMatchesAFineRk4Reference) {
  const SecondOrderStageParams p;
  SecondOrderStage stage(p);
  const double dt = 100e-6;
  const int sub = 1000;
  const double h = dt / sub;
  double y = 0.0;
  double v = 0.0;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> input(-1.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 300; ++i) {
    const double w = input(rng);
    for (int j = 0; j < sub; ++j) {
      auto acc = [&](double yy, double vv) { return -p.k * yy - p.c * vv + p.k * w; };
      const double k1y = v, k1v = acc(y, v);
      const double k2y = v + 0.5 * h * k1v, k2v = acc(y + 0.5 * h * k1y, v + 0.5 * h * k1v);
      const double k3y = v + 0.5 * h * k2v, k3v = acc(y + 0.5 * h * k2y, v + 0.5 * h * k2v);
      const double k4y = v + h * k3v, k4v = acc(y + h * k3y, v + h * k3v);
      y += h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
      v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    worst = std::max(worst, std::abs(stage.step(w, dt) - y));
  }
  std::printf("stage ZOH step (dt = 100 us) vs RK4 with 1000 substeps: max |error| = %.3g (input +-1)\n", worst);
  EXPECT_LT(worst, 1e-11);
}

// Frequency response, including the resonance: (a) at dt = 5 us the sampled response's amplitude
// (least-squares sine fit) is the continuous |G(jw)| to 0.1 % (the hold's sinc(w dt / 2) is
// >= 0.9993 up to 4 kHz); (b) at the bridge's dt = 100 us it is exactly the ZOH-equivalent
// transfer function written from the closed-form step response.
TEST(SecondOrderStage, FrequencyResponseMatchesTheSecondOrderClosedForm) {
  const SecondOrderStageParams p;
  std::printf("   f [Hz]   |G(jw)|  sim@5us   rel err | G_zoh@100us  sim@100us  rel err\n");
  for (double f : {100.0, 500.0, 1000.0, 1500.0, 1720.0, 2500.0, 4000.0}) {
    const double omega = 2.0 * kPi * f;
    const double g = stage_magnitude(p, omega);
    const double fine = simulated_gain(p, f, 5e-6);
    const double gd = zoh_gain(p, omega, 100e-6);
    const double coarse = simulated_gain(p, f, 100e-6);
    std::printf("%9.0f %9.5f %9.5f %+9.1e | %11.6f %10.6f %+9.1e\n", f, g, fine, fine / g - 1.0, gd, coarse,
                coarse / gd - 1.0);
    EXPECT_NEAR(fine, g, 1e-3 * g) << f;
    EXPECT_NEAR(coarse, gd, 1e-8 * gd) << f;
  }
  EXPECT_NEAR(stage_magnitude(p, 0.0), 1.0, 1e-15);             // unit DC gain
  EXPECT_NEAR(stage_magnitude(p, std::sqrt(p.k)), 5.33, 0.01);  // 1 / (2 zeta) at omega_n
}

TEST(SecondOrderStage, BadInputOrDtReturnsNanAndKeepsState) {
  SecondOrderStage stage;
  stage.step(1.0, 1e-4);
  const double y = stage.output();
  EXPECT_TRUE(std::isnan(stage.step(std::nan(""), 1e-4)));
  EXPECT_TRUE(std::isnan(stage.step(1.0, 0.0)));
  EXPECT_TRUE(std::isnan(stage.step(1.0, -1e-4)));
  EXPECT_TRUE(std::isnan(stage.step(1.0, HUGE_VAL)));
  EXPECT_EQ(stage.output(), y);
  stage.reset(0.25);
  EXPECT_NEAR(stage.step(0.25, 1e-4), 0.25, 1e-15);  // at rest
}

// Changing dt recomputes the discretisation: the result equals a stage that only ever used it.
TEST(SecondOrderStage, ChangingDtRediscretises) {
  SecondOrderStage a;
  SecondOrderStage b;
  for (int i = 0; i < 10; ++i) a.step(1.0, 1e-4);
  for (int i = 0; i < 20; ++i) b.step(1.0, 0.5e-4);
  EXPECT_NEAR(a.output(), b.output(), 1e-12);
  for (int i = 0; i < 10; ++i) {
    a.step(-1.0, 0.5e-4);
    b.step(-1.0, 0.5e-4);
  }
  EXPECT_NEAR(a.output(), b.output(), 1e-12);
}

TEST(SecondOrderStage, StepAllocatesNothingEvenWhenDtChanges) {
  SecondOrderStage stage;
  double sink = 0.0;
  hystloop::testing::AllocationCounter counter;
  for (int i = 0; i < 10000; ++i) sink += stage.step(std::sin(0.01 * i), i % 1000 == 0 ? 5e-5 : 1e-4);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

// Seeded property: random stable parameters, steps and bounded inputs. The output stays finite and
// within ||g||_1 max|w|, with ||g||_1 <= 1 / (zeta sqrt(1 - zeta^2)) underdamped and 1 otherwise.
TEST(SecondOrderStage, PropertyRandomParamsAndInputsStayFiniteAndBounded) {
  std::mt19937_64 rng(0x5EC0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < (kSanitized ? 30 : 100); ++trial) {
    SecondOrderStageParams p;
    p.k = std::pow(10.0, 4.0 + 6.0 * unit(rng));
    p.c = std::sqrt(p.k) * std::pow(10.0, -2.0 + 3.0 * unit(rng));  // zeta from 0.005 to 5
    SecondOrderStage stage(p);
    const double z = p.damping_ratio();
    const double l1 = z < 1.0 ? 1.0 / (z * std::sqrt(1.0 - z * z)) : 1.0;
    double dt = 1e-4;
    for (int i = 0; i < 500; ++i) {
      if (i % 50 == 0) dt = std::pow(10.0, -6.0 + 3.0 * unit(rng));  // new dt: re-discretised
      const double y = stage.step(2.0 * unit(rng) - 1.0, dt);
      ASSERT_TRUE(std::isfinite(y));
      ASSERT_LE(std::abs(y), l1 * (1.0 + 1e-9)) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace hystloop
