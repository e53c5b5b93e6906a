// The fitters' shared input check, result stamping and injected clock (ident/fit_clock.hpp):
// with a clock that does not run, a fit is the same on any machine and reports 0 s; a clock that
// jumps past the budget stops Ceres early, so the budget is read from the clock passed in.
#include "ident/fit_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "ident/fit_checks.hpp"
#include "ident/katalenic_fit.hpp"
#include "ident/mem_fit.hpp"
#include "ident/pi_fit.hpp"
#include "models/katalenic.hpp"
#include "models/mem.hpp"

namespace hystloop {
namespace {

std::vector<double> sine(double amp, double f, std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = amp * std::sin(2.0 * std::numbers::pi * f * static_cast<double>(k) * 1e-4);
  return u;
}

TEST(FitInput, RefusesAConstantInputAndReportsTheExtremes) {
  const std::vector<double> u{1.0, 3.0, 2.0}, y{0.0, 0.0, 0.0};
  double lo = 0.0, hi = 0.0;
  ASSERT_TRUE(check_fit_input(u, y, 1.0, &lo, &hi).ok());
  EXPECT_EQ(lo, 1.0);
  EXPECT_EQ(hi, 3.0);
  const FitCheck narrow = check_fit_input(u, y, 2.5);
  EXPECT_EQ(narrow.status, FitStatus::constant_input);
  EXPECT_NE(narrow.reason.find("u spans 2 V"), std::string::npos) << narrow.reason;
  EXPECT_EQ(check_fit_input(std::vector<double>(4, 1.0), std::vector<double>(4, 0.0), 0.0).status,
            FitStatus::constant_input);
  EXPECT_EQ(check_fit_input(u, std::vector<double>{0.0}, 0.0).status, FitStatus::size_mismatch);
}

TEST(FitInput, ScoresFromTheSecondReversal) {
  const auto u = sine(1.0, 10.0, 2000);  // extremes at k = 250 and 750
  std::size_t begin = 0;
  ASSERT_TRUE(check_after_second_reversal(u, 50, &begin).ok());
  EXPECT_NEAR(static_cast<double>(begin), 750.0, 1.0);
  EXPECT_EQ(check_after_second_reversal(u, 1300, &begin).status, FitStatus::too_few_samples);
  std::vector<double> ramp(100);
  for (std::size_t k = 0; k < ramp.size(); ++k) ramp[k] = static_cast<double>(k);
  EXPECT_EQ(check_after_second_reversal(ramp, 1, &begin).status, FitStatus::too_few_branches);
}

TEST(FitTimer, StampsStatusReasonAndTheClocksElapsedTime) {
  double now = 10.0;
  const FitTimer timer([&] { return now; });
  now = 12.5;
  const PiFitResult r = timer.finish(PiFitResult{}, FitCheck{FitStatus::out_of_range, "why"});
  EXPECT_EQ(r.status, FitStatus::out_of_range);
  EXPECT_EQ(r.reason, "why");
  EXPECT_EQ(r.solve_time_s, 2.5);
}

TEST(FitClock, AFixedClockMakesTheMemFitReproducible) {
  const MemParams truth = MemParams::paper_like();
  MemModel model(truth);
  const auto u = sine(200.0, 10.0, 20000);
  std::vector<double> y(u.size());
  model.reset(0.0);
  for (std::size_t k = 0; k < u.size(); ++k)
    y[k] = model.forward(u[k]) + 1e-9 * std::sin(0.37 * static_cast<double>(k));
  MemFitOptions o;
  o.clock = fixed_fit_clock();
  const MemFitResult a = fit_mem(u, y, o), b = fit_mem(u, y, o);
  ASSERT_TRUE(a.ok()) << a.reason;
  EXPECT_EQ(a.solve_time_s, 0.0);
  EXPECT_EQ(a.params.c1, b.params.c1);
  EXPECT_EQ(a.params.c2, b.params.c2);
  EXPECT_EQ(a.params.c3, b.params.c3);
}

TEST(FitClock, CeresReadsItsBudgetFromTheGivenClock) {
  KatalenicParams truth;
  truth.k2_slope = 0.0;
  const auto u = sine(250.0, 10.0, 6000);
  KatalenicModel m(truth);
  m.reset(u[0]);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = m.forward(u[k]);
  KatalenicFitOptions fixed;
  fixed.clock = fixed_fit_clock();
  fixed.max_solver_time_s = 1e-3;  // would stop a wall-clock solve; the fixed clock never reaches it
  const KatalenicFitResult full = fit_katalenic(u, y, fixed);
  ASSERT_TRUE(full.ok()) << full.reason;
  EXPECT_EQ(full.solve_time_s, 0.0);
  EXPECT_NEAR(full.params.k1, truth.k1, 1e-3 * truth.k1);
  // Every read of this clock is an hour later: Ceres stops after its first iteration.
  double t = 0.0;
  KatalenicFitOptions jumping = fixed;
  jumping.clock = [&] { return t += 3600.0; };
  const KatalenicFitResult cut = fit_katalenic(u, y, jumping);
  EXPECT_GE(cut.solve_time_s, 3600.0);
  EXPECT_GT(std::abs(cut.params.k1 - truth.k1), 10.0 * std::abs(full.params.k1 - truth.k1));
}

}  // namespace
}  // namespace hystloop
