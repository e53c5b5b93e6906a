// Iterative learning in the closed loop, seen a horizon late (periodic_learner_rig.hpp), in both
// updates: convergence on known plants as predicted per harmonic, a period shorter than the lag,
// the noise, restarts, fading out, wrong models. The learner's own rules (filter, missing
// samples, idle, allocation, validation, the update's arithmetic) are in periodic_learner_test.cpp;
// the lag-compensated update's stability bound in periodic_learner_lag_test.cpp.
#include "loop/periodic_learner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "periodic_learner_rig.hpp"

namespace hystloop {
namespace {

using testing::disturbance;
using testing::error_without_learning;
using testing::kLearnDt;
using testing::LearningLoop;
using testing::LinearPlant;
using testing::predict;
using testing::Prediction;
using testing::raster;

constexpr double kNm = 1e-9;
constexpr double kSigma = 1e-9;  // the sensor's white noise

LearningConfig with_update(bool lag_compensated) {
  LearningConfig c = testing::stepwise();
  c.lag_compensated = lag_compensated;
  return c;
}
const char* update_name(bool lag_compensated) { return lag_compensated ? "lag-compensated" : "plain"; }

// L for the rig's 500-tick horizon and 20-tick blocks: the table of period p is computed when the
// block with p's last sample arrives, the plan then 480-500 ticks ahead, and adopted at the first
// boundary the plan reaches after that.
std::int64_t rig_chain(std::int64_t n) {
  switch (n) {
    case 1000:
    case 700: return 2;
    case 400: return 3;
    case 200: return 4;
    case 100: return 6;
    case 50: return 11;
    default: return 0;
  }
}

// The error of each period in [from, to) against the prediction: the noise learned adds in
// quadrature and its RMS over one period scatters (2 of it), and a table change is smeared over a
// plant delay's ticks after the boundary, which the harmonic model leaves out (5 %).
void expect_follows_prediction(const LearningLoop& loop, const Prediction& p, std::int64_t n, std::int64_t from,
                               std::int64_t to) {
  for (std::int64_t q = from; q < to; ++q) {
    const double predicted = p.error_rms[static_cast<std::size_t>(q)];
    EXPECT_NEAR(loop.error_rms(q * n, (q + 1) * n), std::hypot(predicted, p.noise_rms),
                0.05 * predicted + 2.0 * p.noise_rms)
        << "period " << q;
  }
}
// An upper bound for the error of period q and later ones of a converging learning.
double bound_at(const Prediction& p, std::int64_t q) {
  return 1.05 * p.error_rms[static_cast<std::size_t>(q)] + 3.0 * p.noise_rms;
}

// Tables are taken into use only at a period boundary of the plan.
void expect_adopted_at_boundaries(const LearningLoop& loop, std::int64_t k0, std::int64_t n, std::int64_t from = 1) {
  for (std::int64_t k = std::max<std::int64_t>(from, 1); k <= loop.planned; ++k) {
    if (loop.adopted[static_cast<std::size_t>(k)] != loop.adopted[static_cast<std::size_t>(k - 1)]) {
      ASSERT_EQ((k - k0) % n, 0) << "a table was adopted mid-period at tick " << k;
    }
  }
}

std::string plant_name(const LinearPlant& p) {
  std::string name =
      "gain" + std::to_string(static_cast<int>(std::lround(p.gain * 10.0))) + "_delay" + std::to_string(p.delay);
  for (char& ch : name) ch = ch == '-' ? 'm' : ch;
  return name;
}

struct Converging {
  LinearPlant plant;
  std::int64_t period;
  bool lag_compensated;
};
void PrintTo(const Converging& c, std::ostream* os) {
  *os << plant_name(c.plant) << ", period " << c.period << ", " << update_name(c.lag_compensated);
}

class LearnerConverges : public ::testing::TestWithParam<Converging> {};

// A raster of 0.5 um with a periodic disturbance, through a gain error or a one-tick lag, seen
// 500-520 ticks late: every period's error is the one predicted per harmonic for the update in
// use (they part after the first table, L periods in), and at period 20 the lag-compensated
// update's error is below the plain one's.
TEST_P(LearnerConverges, AsPredictedOverTwentyPeriods) {
  const LinearPlant plant = GetParam().plant;
  const std::int64_t n = GetParam().period;
  const bool lag_compensated = GetParam().lag_compensated;
  PeriodicLearner learner(with_update(lag_compensated), kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, 22 * n, plant, [n](std::int64_t k) { return raster(k, n, 500 * kNm); },
      [n](std::int64_t k) { return disturbance(k, n); }, kSigma, 7);
  learner.restart(0, n);
  loop.run(22 * n);
  const std::int64_t chain = loop.first_adoption_period(n);
  ASSERT_EQ(chain, rig_chain(n));
  const std::vector<double> e0 = error_without_learning(n, 500 * kNm, plant);
  const Prediction p =
      predict(e0, learner.filter_half_width(), learner.gain(), plant, kSigma, {lag_compensated, chain, 22});
  const Prediction other =
      predict(e0, learner.filter_half_width(), learner.gain(), plant, kSigma, {!lag_compensated, chain, 22});
  ASSERT_LT(p.rate, 1.0);  // the learning is stable on this plant with this Q
  EXPECT_NEAR(loop.error_rms(n, 2 * n), p.e0_rms, 0.05 * p.e0_rms);
  expect_follows_prediction(loop, p, n, 1, 22);
  const double last = loop.error_rms(20 * n, 21 * n);
  const Prediction& lagc = lag_compensated ? p : other;
  const Prediction& plain = lag_compensated ? other : p;
  EXPECT_LT(lagc.error_rms[20], plain.error_rms[20]);
  std::printf(
      "period %4lld (L %2lld), gain %.2f, delay %lld, %-15s: e0 %6.2f nm, period 20 %6.3f nm (predicted %6.3f; "
      "%s: %6.3f), fixed point %6.3f, rate %.3f\n",
      static_cast<long long>(n), static_cast<long long>(chain), plant.gain, static_cast<long long>(plant.delay),
      update_name(lag_compensated), p.e0_rms / kNm, last / kNm, p.error_rms[20] / kNm, update_name(!lag_compensated),
      other.error_rms[20] / kNm, p.steady_rms / kNm, p.rate_e0);
  expect_adopted_at_boundaries(loop, 0, n);
  EXPECT_EQ(learner.figures().periods_skipped, 0u);
  EXPECT_EQ(learner.figures().periods_learned, 22u);
  EXPECT_GE(learner.figures().tables_adopted, static_cast<std::uint64_t>(22 - chain));
  // What the learner reports: period 21's error, which includes the sensor's 1 nm.
  EXPECT_LT(learner.figures().last_error_rms_m, std::hypot(bound_at(p, 21), 1.1 * kSigma));
  EXPECT_GT(learner.figures().correction_rms_m, 0.5 * p.e0_rms);
}

std::vector<Converging> converging_cases() {
  std::vector<Converging> cases;
  for (const bool lag_compensated : {true, false}) {
    for (const std::int64_t n : {50, 100, 200, 400, 1000}) {
      for (const LinearPlant plant :
           {LinearPlant{0.9, 0}, LinearPlant{1.1, 0}, LinearPlant{1.0, 1}, LinearPlant{0.9, 1}}) {
        cases.push_back({plant, n, lag_compensated});
      }
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Plants, LearnerConverges, ::testing::ValuesIn(converging_cases()), [](const auto& param_info) {
  return plant_name(param_info.param.plant) + "_period" + std::to_string(param_info.param.period) +
         (param_info.param.lag_compensated ? "_lag_compensated" : "_plain");
});

// The first period from which every later one is within 5 % (and the noise) of the fixed point.
std::int64_t settled_from(const std::vector<double>& rms, double fixed_point, double noise) {
  auto q = static_cast<std::int64_t>(rms.size());
  while (q > 0 && rms[static_cast<std::size_t>(q - 1)] <= 1.05 * fixed_point + 3.0 * noise) --q;
  return q;
}

// 200 Hz (50 ticks) under a 520-tick lag: a table is adopted 11 periods after the one it was
// learned from. The plain update adds to what was applied then (remembered per tick), not to the
// table in use when the samples arrive (that recursion, c' = Q(c_now + g e_old), is unstable
// here), and so steps each of 11 chains once per 11 periods; the lag-compensated one improves the
// table every period. Both reach the predicted fixed point, each when its recursion says.
TEST(PeriodicLearner, LearnsAPeriodShorterThanTheLag) {
  constexpr std::int64_t n = 50, periods = 200;
  const LinearPlant plant{0.9, 0};
  std::int64_t settled[2] = {0, 0};
  for (const bool lag_compensated : {false, true}) {
    PeriodicLearner learner(with_update(lag_compensated), kLearnDt, testing::kMaxLag);
    LearningLoop loop(
        learner, periods * n, plant, [](std::int64_t k) { return raster(k, n, 300 * kNm); },
        [](std::int64_t k) { return disturbance(k, n); }, kSigma, 11);
    learner.restart(0, n);
    loop.run(periods * n);
    // The first table: not before the first period's samples have arrived, a horizon later.
    const std::int64_t chain = loop.first_adoption_period(n);
    EXPECT_GE(chain * n, n + testing::kHorizon);
    const Prediction p = predict(error_without_learning(n, 300 * kNm, plant), learner.filter_half_width(),
                                 learner.gain(), plant, kSigma, {lag_compensated, chain, periods});
    expect_follows_prediction(loop, p, n, 1, periods);
    std::vector<double> measured;
    for (std::int64_t q = 0; q < periods; ++q) measured.push_back(loop.error_rms(q * n, (q + 1) * n));
    const std::int64_t at = settled_from(measured, p.steady_rms, p.noise_rms);
    const std::int64_t predicted_at = settled_from(p.error_rms, p.steady_rms, p.noise_rms);
    settled[lag_compensated ? 1 : 0] = at;
    std::printf(
        "period 50 under a 520-tick lag (L %lld), %s: e0 %.2f nm, period 20 %.3f nm, settled from period %lld "
        "(predicted %lld), period 199 %.3f nm (fixed point %.3f)\n",
        static_cast<long long>(chain), update_name(lag_compensated), p.e0_rms / kNm, measured[20] / kNm,
        static_cast<long long>(at), static_cast<long long>(predicted_at), measured[periods - 1] / kNm,
        p.steady_rms / kNm);
    EXPECT_NEAR(static_cast<double>(at), static_cast<double>(predicted_at), 3.0);
    // Converged to the predicted fixed point: what is left is the disturbance's fifth harmonic at
    // 1 kHz, the filter's cutoff, learned only in part (Q = 0.59 there).
    EXPECT_NEAR(measured[periods - 1], p.steady_rms, 0.05 * p.steady_rms + 3.0 * p.noise_rms);
    EXPECT_LT(measured[periods - 1], 0.4 * p.e0_rms);
    expect_adopted_at_boundaries(loop, 0, n);
  }
  EXPECT_LT(2 * settled[1], settled[0]);  // the lag-compensated update gets there in less than half the time
}

struct Noisy {
  bool lag_compensated;
  double plant_gain;
};
void PrintTo(const Noisy& c, std::ostream* os) { *os << update_name(c.lag_compensated) << ", plant " << c.plant_gain; }
class LearnerUnderNoise : public ::testing::TestWithParam<Noisy> {};

// White sensor noise alone (200-tick periods, L = 4): the learned signal is stationary (the DC
// does not random-walk) with the variance the recursion predicts. On an exact plant that is,
// in either update, below gain ||q||^2 sigma^2 / (2 - gain); what tells the updates apart is
// whose tables are correlated: neighbours by 1 - gain in the lag-compensated one, tables L apart
// (one chain) in the plain one.
TEST_P(LearnerUnderNoise, StaysWithinTheDerivedVariance) {
  constexpr std::int64_t n = 200, periods = 3000, burn_in = 100;
  const bool lag_compensated = GetParam().lag_compensated;
  const LinearPlant plant{GetParam().plant_gain, 0};
  PeriodicLearner learner(with_update(lag_compensated), kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, periods * n, plant, [](std::int64_t k) { return raster(k, n, 500 * kNm); },
      // What the plant's gain does not pass of the reference, put back: the error is the noise's alone.
      [gain = plant.gain](std::int64_t k) { return (1.0 - gain) * raster(k, n, 500 * kNm); }, kSigma, 3);
  learner.restart(0, n);
  loop.run(periods * n);
  const std::int64_t chain = loop.first_adoption_period(n);
  ASSERT_EQ(chain, rig_chain(n));
  const double g = learner.gain();
  const Prediction p =
      predict(std::vector<double>(n, 0.0), learner.filter_half_width(), g, plant, kSigma, {lag_compensated, chain, 0});
  double sum_sq = 0.0;
  std::vector<double> dc;  // of the table in use, period by period
  for (std::int64_t q = burn_in; q < periods - 1; ++q) {
    double mean = 0.0;
    for (std::int64_t i = 0; i < n; ++i) {
      const double c = loop.corr[static_cast<std::size_t>(q * n + i)];
      sum_sq += c * c;
      mean += c / static_cast<double>(n);
    }
    dc.push_back(mean);
  }
  auto correlation = [&dc](std::size_t lag) {
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < dc.size(); ++i) {
      den += dc[i] * dc[i];
      if (i >= lag) num += dc[i] * dc[i - lag];
    }
    return num / den;
  };
  const auto used = static_cast<double>(periods - 1 - burn_in);
  const double var = sum_sq / (used * static_cast<double>(n));
  const double rho1 = correlation(1), rho_chain = correlation(static_cast<std::size_t>(chain));
  std::printf(
      "noise, %s, plant %.1f: learned RMS %.4f nm (predicted %.4f), true error %.4f nm; DC correlation "
      "%.2f at 1 period, %.2f at %lld\n",
      update_name(lag_compensated), plant.gain, std::sqrt(var) / kNm, std::sqrt(p.correction_var) / kNm,
      p.noise_rms / kNm, rho1, rho_chain, static_cast<long long>(chain));
  EXPECT_NEAR(var, p.correction_var, 0.1 * p.correction_var);
  EXPECT_NEAR(learner.figures().correction_rms_m, std::sqrt(p.correction_var), 0.2 * std::sqrt(p.correction_var));
  EXPECT_EQ(learner.figures().periods_skipped, 0u);
  if (plant.gain == 1.0) {
    const double bound = g * learner.filter_norm_sq() * kSigma * kSigma / (2.0 - g);
    EXPECT_LE(p.correction_var, bound);
    EXPECT_GT(p.correction_var, 0.8 * bound);  // the bound is close, not just safe
    EXPECT_LT(var, 1.1 * bound);
    double mean_sq = 0.0;
    for (const double d : dc) mean_sq += d * d / static_cast<double>(dc.size());
    const double dc_predicted = std::sqrt(g * kSigma * kSigma / ((2.0 - g) * n));
    EXPECT_NEAR(std::sqrt(mean_sq), dc_predicted, 0.25 * dc_predicted);
    // The DC follows C_p = (1 - gain) C_{p-1} - gain N_p (lag-compensated) or the same with C_{p-L}
    // (plain): its correlation is (1 - gain)^(lag / 1 or L). 2800 periods: +-0.02 per standard error.
    const double lag1 = lag_compensated ? 1.0 - g : 0.0;
    const double lag_chain = lag_compensated ? std::pow(1.0 - g, static_cast<double>(chain)) : 1.0 - g;
    EXPECT_NEAR(rho1, lag1, 0.1);
    EXPECT_NEAR(rho_chain, lag_chain, 0.1);
  }
}

INSTANTIATE_TEST_SUITE_P(Updates, LearnerUnderNoise,
                         ::testing::Values(Noisy{true, 1.0}, Noisy{false, 1.0}, Noisy{true, 0.8}, Noisy{false, 0.8}),
                         [](const auto& param_info) {
                           return std::string(param_info.param.lag_compensated ? "lag_compensated" : "plain") +
                                  "_plant" +
                                  std::to_string(static_cast<int>(std::lround(param_info.param.plant_gain * 10)));
                         });

// Over the fade, each tick's step is at most the table's own step plus max_correction / fade.
void expect_faded_without_a_step(const LearningLoop& loop, const PeriodicLearner& learner, std::int64_t from,
                                 std::int64_t period) {
  double own_step = 0.0, largest = 0.0;
  for (std::int64_t k = from - period; k < from; ++k) {
    own_step = std::max(own_step,
                        std::abs(loop.corr[static_cast<std::size_t>(k)] - loop.corr[static_cast<std::size_t>(k - 1)]));
    largest = std::max(largest, std::abs(loop.corr[static_cast<std::size_t>(k)]));
  }
  const double allowed = own_step + LearningConfig{}.max_correction_m / static_cast<double>(learner.fade_ticks());
  ASSERT_GT(largest, 20.0 * allowed);  // dropping the correction at once would fail this test
  for (std::int64_t k = from; k < from + learner.fade_ticks(); ++k) {
    ASSERT_LE(std::abs(loop.corr[static_cast<std::size_t>(k)] - loop.corr[static_cast<std::size_t>(k - 1)]), allowed)
        << "tick " << k;
  }
  EXPECT_EQ(loop.corr[static_cast<std::size_t>(from + learner.fade_ticks() - 1)], 0.0);
}

TEST(PeriodicLearner, RestartFadesTheOldTableOutAndLearnsTheNewReference) {
  constexpr std::int64_t na = 1000, nb = 700;
  const LinearPlant plant{0.9, 0};
  std::int64_t k0 = std::numeric_limits<std::int64_t>::max();  // where reference B begins
  PeriodicLearner learner(testing::stepwise(), kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, 25 * na + 25 * nb, plant,
      [&k0](std::int64_t k) { return k < k0 ? raster(k, na, 500 * kNm) : raster(k - k0, nb, 400 * kNm); },
      [&k0](std::int64_t k) { return k < k0 ? disturbance(k, na) : disturbance(k - k0, nb); }, kSigma, 5);
  learner.restart(0, na);
  loop.run(25 * na + 300);
  k0 = loop.planned + 1;  // the new reference takes effect at the first tick not yet planned
  learner.restart(k0, nb);
  EXPECT_EQ(learner.figures().period_ticks, nb);
  EXPECT_TRUE(learner.figures().fading);
  const std::uint64_t adopted_before = learner.figures().tables_adopted;
  loop.run(25 * nb - 300);
  expect_faded_without_a_step(loop, learner, k0, na);
  // Nothing from A, nothing learned before a whole period of B has been observed.
  const std::int64_t learn_start = k0 + nb;  // the first boundary of B after the fade (500 ticks)
  for (std::int64_t k = k0 + learner.fade_ticks() - 1; k < learn_start + nb + testing::kHorizon; ++k) {
    ASSERT_EQ(loop.corr[static_cast<std::size_t>(k)], 0.0) << k;
  }
  expect_adopted_at_boundaries(loop, k0, nb, k0);
  EXPECT_GT(learner.figures().tables_adopted, adopted_before + 15);
  const Prediction p = predict(error_without_learning(nb, 400 * kNm, plant), learner.filter_half_width(),
                               learner.gain(), plant, kSigma, {true, rig_chain(nb), 21});
  const std::int64_t at = learn_start + 20 * nb;
  EXPECT_LT(loop.error_rms(at, at + nb), bound_at(p, 20));
  EXPECT_TRUE(learner.figures().active);
}

TEST(PeriodicLearner, StopFadesOutAndLearnsNothingMore) {
  constexpr std::int64_t n = 1000;
  PeriodicLearner learner(testing::stepwise(), kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, 30 * n, {0.9, 0}, [](std::int64_t k) { return raster(k, n, 500 * kNm); },
      [](std::int64_t k) { return disturbance(k, n); }, kSigma, 9);
  learner.restart(0, n);
  loop.run(20 * n + 123);
  const std::int64_t from = loop.planned + 1;
  learner.stop();
  EXPECT_TRUE(learner.figures().fading);
  EXPECT_FALSE(learner.figures().active);
  const std::uint64_t learned = learner.figures().periods_learned;
  loop.run(5 * n);
  expect_faded_without_a_step(loop, learner, from, n);
  for (std::int64_t k = from + learner.fade_ticks() - 1; k <= loop.planned; ++k) {
    ASSERT_EQ(loop.corr[static_cast<std::size_t>(k)], 0.0);
  }
  EXPECT_EQ(learner.figures().periods_learned, learned);
  EXPECT_FALSE(learner.figures().fading);
  EXPECT_EQ(learner.figures().period_ticks, 0);
  EXPECT_EQ(learner.figures().correction_rms_m, 0.0);
}

// Off fades out like stop; on learns the same period again from zero. reset() does both at once.
TEST(PeriodicLearner, OffOnAndResetFadeOutThenLearnAgain) {
  constexpr std::int64_t n = 1000;
  const LinearPlant plant{0.9, 0};
  PeriodicLearner learner(testing::stepwise(), kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, 75 * n, plant, [](std::int64_t k) { return raster(k, n, 500 * kNm); },
      [](std::int64_t k) { return disturbance(k, n); }, kSigma, 13);
  // The learning starts again at a period boundary each time; 22 periods later it is past period 20.
  const Prediction p = predict(error_without_learning(n, 500 * kNm, plant), learner.filter_half_width(), learner.gain(),
                               plant, kSigma, {true, rig_chain(n), 21});
  learner.restart(0, n);
  loop.run(20 * n + 400);
  std::int64_t from = loop.planned + 1;
  learner.set_enabled(false);
  EXPECT_FALSE(learner.enabled());
  loop.run(3 * n);
  expect_faded_without_a_step(loop, learner, from, n);
  EXPECT_EQ(loop.corr[static_cast<std::size_t>(loop.planned)], 0.0);
  EXPECT_GT(loop.error_rms(loop.now - n, loop.now), 0.9 * p.e0_rms);  // the error is back
  learner.set_enabled(true);
  EXPECT_TRUE(learner.figures().active);
  loop.run(24 * n);
  EXPECT_LT(loop.error_rms(loop.now - n, loop.now), bound_at(p, 20));

  from = loop.planned + 1;
  const std::uint64_t adopted = learner.figures().tables_adopted;
  learner.reset();
  EXPECT_EQ(learner.figures().period_ticks, n);
  loop.run(3 * n);
  expect_faded_without_a_step(loop, learner, from, n);
  EXPECT_GT(loop.error_rms(loop.now - n, loop.now), 0.5 * p.e0_rms);  // forgotten
  loop.run(22 * n);
  EXPECT_LT(loop.error_rms(loop.now - n, loop.now), bound_at(p, 20));
  EXPECT_GT(learner.figures().tables_adopted, adopted + 20);
  expect_adopted_at_boundaries(loop, 0, n);
}

struct WrongModel {
  LinearPlant plant;
  bool contracting;
  std::int64_t period;
  bool lag_compensated;
};
void PrintTo(const WrongModel& w, std::ostream* os) {
  *os << plant_name(w.plant) << ", period " << w.period << ", " << update_name(w.lag_compensated);
}
class LearnerWithAWrongModel : public ::testing::TestWithParam<WrongModel> {};

// A plant gain of 0.5 or 1.5, or 3 ticks of delay: still stable with this Q, in either update and
// at every lag of the rig; the error never grows and goes as predicted. Gain -1 (the model's sign
// wrong) or 8 ticks of delay: unstable, but the table stays inside max_correction_m, so the error
// stays within what the clamp allows.
TEST_P(LearnerWithAWrongModel, StaysBoundedAndTheErrorDoesNotGrow) {
  const LinearPlant plant = GetParam().plant;
  const bool contracting = GetParam().contracting;
  const std::int64_t n = GetParam().period;
  constexpr std::int64_t periods = 40;
  const LearningConfig config = with_update(GetParam().lag_compensated);
  PeriodicLearner learner(config, kLearnDt, testing::kMaxLag);
  LearningLoop loop(
      learner, periods * n, plant, [n](std::int64_t k) { return raster(k, n, 100 * kNm); },
      [n](std::int64_t k) { return disturbance(k, n); }, kSigma, 17);
  learner.restart(0, n);
  loop.run(periods * n);
  const std::int64_t chain = loop.first_adoption_period(n);
  ASSERT_EQ(chain, rig_chain(n));
  const std::vector<double> e0 = error_without_learning(n, 100 * kNm, plant);
  const Prediction p = predict(e0, learner.filter_half_width(), learner.gain(), plant, kSigma,
                               {config.lag_compensated, chain, static_cast<int>(periods)});
  EXPECT_EQ(p.rate < 1.0, contracting) << "largest root per period " << p.rate;
  const double largest = loop.largest_correction();
  EXPECT_LE(largest, config.max_correction_m);
  // Period 1: no table yet (the first is adopted at period L), the delay's start-up is over.
  const double first = loop.error_rms(n, 2 * n);
  std::printf("%s, period %lld, %s: rate %.3f, max |c| %.1f nm, error period 1 %.2f nm, period %lld %.2f nm\n",
              plant_name(plant).c_str(), static_cast<long long>(n), update_name(config.lag_compensated), p.rate,
              largest / kNm, first / kNm, static_cast<long long>(periods - 1),
              loop.error_rms((periods - 1) * n, periods * n) / kNm);
  if (contracting) {
    for (std::int64_t q = 2; q < periods; ++q) EXPECT_LE(loop.error_rms(q * n, (q + 1) * n), first + 0.5 * kNm) << q;
    expect_follows_prediction(loop, p, n, 1, periods);
  } else {
    double e0_max = 0.0;
    for (const double e : e0) e0_max = std::max(e0_max, std::abs(e));
    for (std::int64_t k = 2 * n; k < periods * n; ++k) {
      ASSERT_LE(std::abs(loop.ref[static_cast<std::size_t>(k)] - loop.y[static_cast<std::size_t>(k)]),
                e0_max + std::abs(plant.gain) * config.max_correction_m + 1e-15);
    }
  }
}

std::vector<WrongModel> wrong_models() {
  std::vector<WrongModel> cases;
  for (const bool lag_compensated : {true, false}) {
    for (const std::int64_t n : {50, 100, 200, 1000}) {
      for (const auto& [plant, contracting] :
           {std::pair{LinearPlant{0.5, 0}, true}, std::pair{LinearPlant{1.5, 0}, true},
            std::pair{LinearPlant{1.0, 3}, true}, std::pair{LinearPlant{-1.0, 0}, false},
            std::pair{LinearPlant{1.0, 8}, false}}) {
        cases.push_back({plant, contracting, n, lag_compensated});
      }
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Plants, LearnerWithAWrongModel, ::testing::ValuesIn(wrong_models()),
                         [](const auto& param_info) {
                           return plant_name(param_info.param.plant) + "_period" +
                                  std::to_string(param_info.param.period) +
                                  (param_info.param.lag_compensated ? "_lag_compensated" : "_plain");
                         });

}  // namespace
}  // namespace hystloop
