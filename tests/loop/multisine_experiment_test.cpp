// The multisine experiment: its wire grammar, its voltage at the loop's tick (lines only, ramps at
// both ends, the record in design_multisine's layout), the compensator's refusals naming the
// limit, and a queue that reads it without allocating.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "loop/compensator.hpp"
#include "loop/compensator_rig.hpp"
#include "loop/experiment.hpp"
#include "loop/experiment_queue.hpp"
#include "models/multisine.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;

std::string field_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "";
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.what();
  }
  return "";
}

// f_min 50 Hz, f_max 1 kHz, rms 5 V about 10 V, 20 ms periods (200 ticks, 50 Hz lines), 4 periods,
// 3 realisations.
ExperimentSpec spec() {
  return make_experiment_spec("multisine f_min=50 periods=4 realisations=3 seed=7", 5.0, 10.0, 1000.0, 0.02);
}

// |X(k)| of one period (DFT scaling 2/N: a cosine of amplitude A reads A).
double line_amplitude(const std::vector<double>& u, std::size_t begin, std::size_t n, std::size_t k) {
  std::complex<double> x = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    x += u[begin + j] * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(k * j) / static_cast<double>(n));
  }
  return 2.0 * std::abs(x) / static_cast<double>(n);
}

TEST(MultisineExperiment, TheGrammarRoundTripsAndNamesWhatIsWrong) {
  const ExperimentSpec s = spec();
  EXPECT_TRUE(s.multisine);
  EXPECT_EQ(s.ms.f_min_hz, 50.0);
  EXPECT_EQ(s.ms.periods, 4u);
  EXPECT_EQ(s.ms.realisations, 3u);
  EXPECT_EQ(s.ms.seed, 7u);
  EXPECT_EQ(format_multisine_kind(s.ms), "multisine f_min=50 periods=4 realisations=3 seed=7");
  const ExperimentSpec again = make_experiment_spec(format_multisine_kind(s.ms), 5.0, 10.0, 1000.0, 0.02);
  EXPECT_EQ(again.ms.seed, 7u);
  auto make = [](const char* kind) { return [kind] { make_experiment_spec(kind, 5.0, 0.0, 1000.0, 0.02); }; };
  EXPECT_NE(message_of(make("multisine periods=4")).find("f_min=HZ is required"), std::string::npos);
  EXPECT_NE(message_of(make("multisine f_min=5 f_min=6")).find("given twice"), std::string::npos);
  EXPECT_NE(message_of(make("multisine f_min=5 colour=red")).find("unknown key"), std::string::npos);
  EXPECT_NE(message_of(make("multisine f_min=five")).find("not a number"), std::string::npos);
  EXPECT_EQ(field_of(make("multisine f_min=2000")), "experiment.f_min");
  EXPECT_EQ(field_of(make("multisine f_min=5 periods=2")), "experiment.periods");
  EXPECT_EQ(field_of(make("square")), "experiment");
  ExperimentSpec odd_period = spec();
  odd_period.duration_s = 0.02005;  // 200.5 ticks
  EXPECT_EQ(field_of([&] { prepare_experiment(odd_period, kDt); }), "experiment_duration_s");
}

TEST(MultisineExperiment, PowerOnlyAtTheLinesAndRampsAtBothEnds) {
  ExperimentSpec s = spec();
  prepare_experiment(s, kDt);
  const MultisineSamples& m = *s.samples;
  const std::size_t n = 200;
  ASSERT_EQ(m.period_samples, n);
  ASSERT_EQ(m.ramp_samples, n);
  ASSERT_EQ(m.record_samples, n * 3 * 4);  // realisations x periods x the period
  ASSERT_EQ(m.u_V.size(), m.record_samples + std::size_t{2} * n);
  ASSERT_EQ(m.lines.size(), 20u);  // 50 .. 1000 Hz every 50 Hz
  // Starts and ends at the offset, and moves little per tick there (no step).
  EXPECT_DOUBLE_EQ(m.u_V.front(), 10.0);
  EXPECT_NEAR(m.u_V.back(), 10.0, 1e-12);
  EXPECT_LT(std::abs(m.u_V[1] - 10.0), 0.01);
  EXPECT_LT(std::abs(m.u_V[m.u_V.size() - 2] - 10.0), 0.01);
  // Every period after each realisation's first is design_multisine's record, unchanged.
  MultisineOptions o;
  o.sample_rate_Hz = 1.0 / kDt;
  o.period_samples = n;
  o.f_min_Hz = 50.0;
  o.f_max_Hz = 1000.0;
  o.amplitude_V = 5.0;
  o.offset_V = 10.0;
  o.periods = 4;
  o.realisations = 3;
  o.seed = 7;
  const Multisine d = design_multisine(o);
  for (std::size_t k = 0; k < d.u_V.size(); ++k) {
    if ((k / n) % 4 == 0 && k >= 4 * n) continue;  // a cross-faded transient period
    ASSERT_DOUBLE_EQ(m.u_V[n + k], d.u_V[k]) << k;
  }
  // A steady period: the lines at the designed amplitude, nothing anywhere else.
  const double a = d.line_amplitude_V[1];
  for (std::size_t k = 1; k < n / 2; ++k) {
    const double x = line_amplitude(m.u_V, n + 5 * n, n, k);
    if (k >= 1 && k <= 20) {
      EXPECT_NEAR(x, a, 1e-9 * a) << k;
    } else {
      EXPECT_LT(x, 1e-9 * a) << k;
    }
  }
  EXPECT_NEAR(a * std::sqrt(20.0 / 2.0), 5.0, 1e-9);  // rms 5 V
}

TEST(MultisineExperiment, TheCompensatorRefusesNamingTheLimit) {
  CompensatorConfig c = testing::compensator_config(FeedforwardMode::kMem, 50);
  c.u_min_V = -250.0;  // a real actuator's limits
  c.u_max_V = 250.0;
  c.slew_V_per_s = 5e4;
  c.slew_fraction = CompensatorConfig{}.slew_fraction;
  Compensator comp(c);
  // Peak 60 V about 200 V leaves [-250, 250] V (slowly: 5 .. 50 Hz, within the slew limit).
  const ExperimentSpec wide = make_experiment_spec("multisine f_min=5 amplitude=peak", 60.0, 200.0, 50.0, 0.2);
  const std::string range = message_of([&] { comp.start_experiment(wide); });
  EXPECT_NE(range.find("actuator.u_min_V/u_max_V"), std::string::npos) << range;
  // 20 V rms up to 4 kHz: inside the range, far above the 5e4 V/s limit.
  const ExperimentSpec fast = make_experiment_spec("multisine f_min=50", 20.0, 0.0, 4000.0, 0.02);
  const std::string slew = message_of([&] { comp.start_experiment(fast); });
  EXPECT_NE(slew.find("actuator.slew_V_per_s"), std::string::npos) << slew;
  EXPECT_FALSE(comp.experiment_running());
  // 0.5 V rms to 1 kHz: within both.
  EXPECT_NO_THROW(comp.start_experiment(make_experiment_spec("multisine f_min=50", 0.5, 0.0, 1000.0, 0.02)));
  EXPECT_TRUE(comp.experiment_running());
}

TEST(MultisineExperiment, TheQueueCommandsTheSamplesPerTickWithoutAllocating) {
  ExperimentSpec s = spec();
  prepare_experiment(s, kDt);
  ExperimentSpec sine = make_experiment_spec("sine", 1.0, 0.0, 50.0, 0.02);
  ExperimentQueue q;
  q.add(s);
  q.add(sine);
  q.add(s);
  const std::vector<double>& u = s.samples->u_V;
  const std::int64_t first = 1000;
  std::size_t active = 0;
  testing::AllocationCounter counter;
  for (std::int64_t k = first; k < first + static_cast<std::int64_t>(2 * u.size() + 400); ++k) {
    const ExperimentQueue::Step st = q.step(static_cast<double>(k) * kDt);
    if (!st.active) break;
    const auto i = static_cast<std::size_t>(k - first);
    if (i < u.size()) {
      ASSERT_DOUBLE_EQ(st.voltage_V, u[i]) << i;
    }
    ++active;
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(active, 2 * u.size() + 200);
  // Not prepared: refused where it is queued.
  EXPECT_EQ(field_of([&] { q.add(spec()); }), "experiment");
}

}  // namespace
}  // namespace hystloop
